"""The example notebook (python/examples/demo-figures.ipynb) runs from top to bottom on a small
`pcr demo` output in a headless kernel, and shows every figure it draws."""
import os
import time

import pytest

nbformat = pytest.importorskip("nbformat", reason="nbformat is not installed (scripts/run.sh "
                               "setup installs it with nbclient and ipykernel)")
nbclient = pytest.importorskip("nbclient", reason="nbclient is not installed (scripts/run.sh "
                               "setup installs it with nbformat and ipykernel)")
pytest.importorskip("ipykernel", reason="ipykernel is not installed (scripts/run.sh setup "
                    "installs it with nbclient and nbformat)")

EXAMPLES = os.path.join(os.path.dirname(__file__), "..", "examples")


def test_the_demo_notebook_draws_its_figures(demo_output, monkeypatch):
    monkeypatch.setenv("PCR_DEMO", str(demo_output))
    monkeypatch.delenv("MPLBACKEND", raising=False)  # the notebook's %matplotlib inline
    notebook = nbformat.read(os.path.join(EXAMPLES, "demo-figures.ipynb"), as_version=4)
    client = nbclient.NotebookClient(notebook, timeout=600, kernel_name="python3",
                                     resources={"metadata": {"path": EXAMPLES}})
    start = time.monotonic()
    client.execute()  # raises CellExecutionError, with the cell and the traceback, on an error
    print(f"executed in {time.monotonic() - start:.1f} s")
    outputs = [o for cell in notebook.cells if cell.cell_type == "code" for o in cell.outputs]
    images = [o for o in outputs if "image/png" in o.get("data", {})]
    # Figures 8-9 (one), 11-12 (the square and the circle, each model), three maps.
    assert len(images) == 1 + 4 + 3
    text = "".join(o.get("text", "") for o in outputs)
    assert "reachable positions have a predicted 3-sigma position error above 1 um" in text
