"""Writing trackreplay logs: MCAP writer, sources, synthetic scenes, salvage."""
