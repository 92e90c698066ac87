"""The reproduction pipeline end to end at the tiny scale: every stage, then a rerun that skips them all (slow)."""

import json
import os
import subprocess
import sys

import pytest
from helpers import ROOT


@pytest.mark.slow
def test_pipeline_runs_and_resumes(tmp_path):
    out = str(tmp_path / "results")
    command = [sys.executable, os.path.join(ROOT, "experiments", "reproduce.py"), "--scale", "tiny", "--out", out,
               "--no-report"]
    first = subprocess.run(command, cwd=ROOT, capture_output=True, text=True)
    assert first.returncode == 0, first.stderr[-2000:]
    with open(os.path.join(out, "manifest.json")) as f:
        stages = json.load(f)["stages"]
    assert len(stages) == 5 + 8  # 5 evolutions (EE-ES once), 4 learning tests per variant
    for variant in ("paper", "extension"):
        for condition in ("LE-LS", "EE-LS", "EE-ES", "SLE"):
            assert os.path.exists(os.path.join(out, variant, "test", condition, "steady.json"))
    # An interrupted learning test (no steady.json) is run again; everything else is skipped.
    os.remove(os.path.join(out, "extension", "test", "SLE", "steady.json"))
    second = subprocess.run(command, cwd=ROOT, capture_output=True, text=True)
    assert second.returncode == 0, second.stderr[-2000:]
    assert second.stdout.count(": done (") == 6 + 7  # extension EE-ES is paper's run: "done" both times
    assert "== learning test extension SLE\n" in second.stdout
    assert "imrl_jax.evolve" not in second.stdout
