"""The notebooks: quickstart.ipynb runs top to bottom at a tiny scale; reproduce.ipynb is
only checked for form (it needs a GPU and hours)."""

import pathlib

import nbformat
from nbclient import NotebookClient

NOTEBOOKS = pathlib.Path(__file__).resolve().parent.parent / "notebooks"

TINY_PARAMETERS = '''REPO_URL = "unused: the package is installed"
EXTRA = ""
RUN = "runs/tiny"
CHANGES = dict(tasks=("valve1",), steps=2, num_envs=4, unroll_length=5, num_minibatches=2,
               update_epochs=1, eval_every=0, eval_envs=2, checkpoint_every=0)
TASK = "valve1"
RENDER_FLAGS = ["--camera", "front", "--height", "96", "--width", "128"]'''


def parameters_cell(notebook):
  (cell,) = [c for c in notebook.cells if "parameters" in c.metadata.get("tags", [])]
  return cell


def test_quickstart_notebook_runs_top_to_bottom(tmp_path):
  notebook = nbformat.read(NOTEBOOKS / "quickstart.ipynb", as_version=4)
  parameters_cell(notebook).source = TINY_PARAMETERS
  # raises CellExecutionError, with the cell and its traceback, if any cell fails
  NotebookClient(notebook, timeout=600, kernel_name="python3",
                 resources={"metadata": {"path": str(tmp_path)}}).execute()

  run = tmp_path / "runs" / "tiny"
  assert sorted(p.name for p in (run / "plots").iterdir()) == ["losses.png", "return.png", "success.png"]
  assert (run / "synergies" / "postures.png").is_file() and (run / "synergies" / "matrix.png").is_file()
  assert (run / "videos" / "valve1.mp4").stat().st_size > 1000
  outputs = [o for c in notebook.cells if c.cell_type == "code" for o in c.outputs]
  shown = [o for o in outputs if o.output_type == "display_data"]
  assert sum("image/png" in o.data for o in shown) == 5  # 3 curves, postures, matrix
  assert sum("<video" in o.data.get("text/html", "") for o in shown) == 1
  printed = "".join(o.get("text", "") for o in outputs if o.output_type == "stream")
  assert "40 env steps  valve1:" in printed  # the progress callback: 1 task x 4 envs x 5 steps x 2


def test_reproduce_notebook_is_valid_and_runs_the_gpu_experiments_and_report():
  notebook = nbformat.read(NOTEBOOKS / "reproduce.ipynb", as_version=4)
  nbformat.validate(notebook)
  assert notebook.metadata["accelerator"] == "GPU"
  code = "\n".join(c.source for c in notebook.cells if c.cell_type == "code")
  assert "discosyn experiment all --scale gpu --out runs/experiments" in code
  assert "discosyn report runs/experiments/* --out report" in code
  assert '"[gpu]"' in parameters_cell(notebook).source
