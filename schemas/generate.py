"""Regenerate ``schemas/_gen/*_pb2.py`` from ``schemas/proto`` (needs ``grpcio-tools``).

Run ``python -m schemas.generate``; ``tests/schemas/test_generated.py`` checks the
committed files are current when grpcio-tools is installed.
"""

from __future__ import annotations

import sys
import tempfile
from pathlib import Path

PROTO_DIR = Path(__file__).parent / "proto"
GEN_DIR = Path(__file__).parent / "_gen"


def generate(out_dir: Path) -> list[Path]:
    """Compile every ``.proto`` under ``proto/trackreplay`` into ``out_dir``."""
    import grpc_tools
    from grpc_tools import protoc

    include = Path(grpc_tools.__file__).parent / "_proto"
    protos = sorted((PROTO_DIR / "trackreplay").glob("*.proto"))
    with tempfile.TemporaryDirectory() as tmp:
        args = ["protoc", f"-I{PROTO_DIR}", f"-I{include}", f"--python_out={tmp}"]
        if protoc.main(args + [str(p) for p in protos]) != 0:
            raise RuntimeError("protoc failed")
        written = []
        for src in sorted((Path(tmp) / "trackreplay").glob("*_pb2.py")):
            dst = out_dir / src.name
            dst.write_bytes(src.read_bytes())
            written.append(dst)
    return written


if __name__ == "__main__":
    for path in generate(GEN_DIR):
        print(path, file=sys.stderr)
