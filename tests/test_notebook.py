"""docs/notebook.ipynb runs from top to bottom without a display, in a fresh kernel of this Python."""

from __future__ import annotations

from pathlib import Path

import pytest

NOTEBOOK = Path(__file__).resolve().parents[1] / "docs" / "notebook.ipynb"


def test_the_example_notebook_runs_and_ends_with_the_export(tmp_path: Path) -> None:
    """About 10-15 s: a 24-frame scene synthesised, replayed, evaluated, smoothed and exported."""
    nbformat = pytest.importorskip("nbformat")
    nbclient = pytest.importorskip("nbclient")
    pytest.importorskip("ipykernel")
    notebook = nbformat.read(NOTEBOOK, as_version=4)
    assert not any(cell.get("outputs") for cell in notebook.cells if cell.cell_type == "code"), "commit it without outputs"
    nbclient.NotebookClient(notebook, timeout=300, kernel_name="python3",
                            resources={"metadata": {"path": str(tmp_path)}}).execute()
    code = [cell for cell in notebook.cells if cell.cell_type == "code"]
    assert not [o for cell in code for o in cell.outputs if o.output_type == "error"]
    last = "".join(o.get("text", "") for o in code[-1].outputs if o.output_type == "stream")
    assert last.strip() == "exported 24 rows; read back 24 rows of 29 columns"
    digest = "".join(o.get("text", "") for cell in code if "replay_log" in cell.source for o in cell.outputs
                     if o.output_type == "stream")
    assert len(digest.strip()) == 64  # the replay's digest, printed
    metrics = next(cell for cell in code if "tr.evaluate(log_path, result)" in cell.source)
    assert "centre_error_mean" in metrics.outputs[0]["data"]["text/plain"]
