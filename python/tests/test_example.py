"""examples/python/gain_tuning.py runs (a reduced sweep) and writes its plot."""
import os
import subprocess
import sys

from conftest import ROOT


def test_gain_tuning_writes_its_plot(tmp_path):
    out = tmp_path / "plots" / "gain_tuning.png"
    run = subprocess.run([sys.executable, str(ROOT / "examples" / "python" / "gain_tuning.py"),
                          str(out), "--quick"], capture_output=True, text=True, timeout=300,
                         env=dict(os.environ, MPLBACKEND="Agg"))
    assert run.returncode == 0, run.stderr
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    lines = run.stdout.splitlines()
    assert lines[0].split() == ["stiffness", "PGS", "rms", "error", "TGS", "rms", "error"]
    rows = [list(map(float, line.split())) for line in lines[1:5]]
    assert len(rows) == 4 and all(len(r) == 3 for r in rows)
    # Stiffer drives track better: the error at the largest stiffness is below the smallest's.
    for col in (1, 2):
        assert rows[-1][col] < rows[0][col]
