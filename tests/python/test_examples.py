"""The Python examples (examples/python/) run as a user would run them."""
import os
import subprocess
import sys

import pytest

import meshflow

EXAMPLES = os.path.join(os.environ["MESHFLOW_SOURCE_DIR"], "examples", "python")


@pytest.mark.parametrize("script,output", [("reconstruct.py", "mesh.ply"), ("fuse.py", "fused.ply"),
                                           ("live.py", None)])
def test_example_runs(script, output, tmp_path):
    args = [sys.executable, os.path.join(EXAMPLES, script)]
    if script == "live.py":
        args += ["--frames", "10"]
    # The module this test imported, whatever the working directory.
    env = dict(os.environ, PYTHONPATH=os.path.dirname(os.path.abspath(meshflow.__file__)))
    done = subprocess.run(args, cwd=tmp_path, env=env, capture_output=True, text=True,
                          timeout=120)
    assert done.returncode == 0, done.stderr
    if output:
        assert (tmp_path / output).stat().st_size > 1000
        assert "wrote" in done.stdout
