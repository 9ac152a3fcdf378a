"""Reading logs, bundling frames, the deterministic replay engine, Rerun, export and eval."""
