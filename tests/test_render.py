"""``python -m imrl_jax.render``: a GIF of the best individual of a tiny run, and bad input."""

import csv
import os

import numpy as np
import pytest
from PIL import Image

from imrl_jax.commands import render


def test_gif_of_the_best_individual(tiny_run, tmp_path):
    out = tmp_path / "new" / "best.gif"
    summary = render.run(tiny_run, 6, str(out), steps=12, every=2)
    with Image.open(out) as image:
        assert image.format == "GIF"
        assert image.n_frames == 6 == summary["frames"]
    assert os.listdir(out.parent) == ["best.gif"]  # the temporary file is gone

    # The best individual over all seeds of the last generation, reliving the life that
    # earned its fitness (the run's keys): same fitness, same task performances as history.csv.
    with np.load(os.path.join(tiny_run, "final_population.npz")) as data:
        fitness = data["fitness"]
    assert summary["fitness"] == fitness.max() > 0
    assert summary["relived_fitness"] == pytest.approx(summary["fitness"], abs=1e-6)
    with open(os.path.join(tiny_run, "history.csv")) as f:
        rows = [r for r in csv.DictReader(f) if int(r["seed"]) == summary["seed"]]
    assert summary["task_performance"] == pytest.approx(float(rows[-1]["best_task6"]), abs=1e-5)


def test_cli_writes_and_refuses_to_overwrite(tiny_run, tmp_path, capsys):
    out = tmp_path / "a.gif"
    out.write_bytes(b"keep me")
    assert render.main([tiny_run, "--task", "1", "--out", str(out), "--steps", "2", "--every", "1"]) == 2
    assert out.read_bytes() == b"keep me"
    assert "exists" in capsys.readouterr().err


@pytest.mark.parametrize("case", ["missing run", "not a run", "task 0", "task 7", "extension", "mp4 without ffmpeg",
                                  "directory", "under a file"])
def test_bad_input(case, tiny_run, tmp_path, capsys, monkeypatch):
    run_dir, task, out = tiny_run, "1", str(tmp_path / "x.gif")
    if case == "missing run":
        run_dir = str(tmp_path / "nothing")
    elif case == "not a run":
        run_dir = str(tmp_path / "empty")
        os.makedirs(run_dir)
    elif case in ("task 0", "task 7"):
        task = case.split()[1]
    elif case == "extension":
        out = str(tmp_path / "x.avi")
    elif case == "mp4 without ffmpeg":
        out = str(tmp_path / "x.mp4")
        monkeypatch.setattr(render.shutil, "which", lambda name: None)
    elif case == "directory":
        out = str(tmp_path / "dir.gif")
        os.makedirs(out)
    elif case == "under a file":
        (tmp_path / "file").write_text("kept")
        out = str(tmp_path / "file" / "x.gif")
    before = sorted(os.listdir(tmp_path))
    assert render.main([run_dir, "--task", task, "--out", out, "--steps", "2"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("error: ") and "\n" not in err
    assert sorted(os.listdir(tmp_path)) == before  # nothing written


@pytest.mark.parametrize("options, message", [
    (["--steps", "100000000000"], "--steps: 100,000,000,000 is above the limit of 100,000"),  # was an OverflowError
    (["--steps", "200000000"], "--steps: 200,000,000 is above the limit of 100,000"),  # ran for minutes
    (["--steps", "20000"], "--steps / --every: 10,000 frames is above the limit of 5,000 (raise --every)"),
    (["--fps", "1000000"], "--fps: 1,000,000 is above the limit of 100"),
    (["--every", "0"], "--steps, --every and --fps must be at least 1"),
    (["--steps", "1e3"], "argument --steps: invalid int value: '1e3'"),  # argparse's errors are one line too
])
def test_absurd_sizes_are_refused_before_the_run_is_read(tmp_path, capsys, options, message):
    out = tmp_path / "x.gif"
    assert render.main([str(tmp_path / "no-run"), "--task", "1", "--out", str(out), *options]) == 2
    assert capsys.readouterr().err == f"error: {message}\n"
    assert os.listdir(tmp_path) == []


def test_the_path_legend_names_only_expressed_experts():
    """LE-LS-N: an unexpressed expert never drives, so the legend leaves it out and keeps the others' numbers."""
    from imrl_jax.analysis.arena_figures import legend_experts

    assert legend_experts(3) == [0, 1, 2]
    assert legend_experts(6, np.array([1.0, 0.0, 0.0, 1.0, 0.0, 0.0])) == [0, 3]
    assert legend_experts(4, np.array([0.0, 0.0, 1.0])) == [2, 3]  # an expert beyond the mask is named


def test_an_animation_is_written_by_its_extensions_writer_and_another_is_refused_naming_the_ones_that_work():
    """plotting.animation_writer, shared by the arena's and XLand's drawings (the command refuses earlier)."""
    from matplotlib.animation import FFMpegWriter, PillowWriter

    from imrl_jax.analysis.plotting import animation_writer

    assert isinstance(animation_writer("a/b.GIF", 5), PillowWriter) and isinstance(animation_writer("b.mp4", 5),
                                                                                 FFMpegWriter)
    with pytest.raises(ValueError, match=r"^unknown format \.avi \(use \.gif or \.mp4\)$"):
        animation_writer("x.avi", 5)
    with pytest.raises(ValueError, match=r"^unknown format \.webm \(use \.png, \.gif or \.mp4\)$"):
        animation_writer("x.webm", 5, stills=(".png",))
