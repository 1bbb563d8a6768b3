"""Every ```python block of README.md runs as written, as its own script, from a temporary
working directory (data files come from featherdrive.example_path, not the cwd)."""
import os
import re
import subprocess
import sys

import pytest

import featherdrive as fd
from conftest import ROOT

BLOCKS = re.findall(r"```python\n(.*?)```", (ROOT / "README.md").read_text(), re.S)


def test_the_readme_has_python_blocks():
    assert len(BLOCKS) >= 2


@pytest.mark.parametrize("index", range(len(BLOCKS)))
def test_readme_python_block_runs_from_any_directory(index, tmp_path):
    env = dict(os.environ, PYTHONPATH=os.path.dirname(fd.__file__), MPLBACKEND="Agg")
    run = subprocess.run([sys.executable, "-c", BLOCKS[index]], cwd=tmp_path, env=env,
                         capture_output=True, text=True)
    assert run.returncode == 0, f"block {index}:\n{BLOCKS[index]}\n{run.stderr}"
