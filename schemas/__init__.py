"""Message schemas of trackreplay logs (protobuf files in ``proto/``) and their typed records."""
