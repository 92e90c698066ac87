"""The demo (the tasks solved beside a random individual) and the figures' conventions."""

import json
import os

import numpy as np
import pytest

from imrl_jax.analysis import arena_figures, charts, controllers, plotting
from imrl_jax.commands import demo
from imrl_jax.world import tasks


def test_demo_shows_the_tasks_solved_beside_a_random_individual(tiny, tmp_path):
    config = tiny("EE-LS")
    summary = demo.run(config, str(tmp_path / "demo"), seed=0)
    assert sorted(os.listdir(tmp_path / "demo")) == ["summary.json", "trajectories.png"]
    with open(tmp_path / "demo" / "summary.json") as f:
        assert json.load(f) == summary
    assert len(summary["performance"]) == 6
    assert min(summary["composition_performance"]) > 0.7  # a competent driver on every task


def test_demo_refuses_an_unwritable_out(tmp_path, capsys):
    blocker = tmp_path / "file"
    blocker.write_text("kept")
    assert demo.main(["--out", str(blocker / "demo")]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("error: --out: cannot write to") and len(err.splitlines()) == 1
    assert os.listdir(tmp_path) == ["file"]


@pytest.mark.parametrize("args, message", [
    (["--seed", "x"], "error: argument --seed: invalid int value: 'x'"),
    (["--condition", "XX"], "error: argument --condition: invalid choice: 'XX'"),
])
def test_a_bad_value_is_one_line_exit_2(tmp_path, capsys, args, message):
    out = tmp_path / "demo"
    assert demo.main([*args, "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith(message) and len(err.splitlines()) == 1
    assert not out.exists()


def test_an_empty_out_is_refused(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert demo.main(["--out", ""]) == 2
    assert capsys.readouterr().err == "error: --out: empty path; give a directory\n"
    assert os.listdir(tmp_path) == []


def test_composition_trajectories_agree_with_its_reaches(tiny):
    config = tiny("EE-LS")
    paths = controllers.trajectories(config, 300)
    reaches = np.asarray(controllers.run_many(config, 300, np.arange(6), np.arange(6)))
    assert [int(p.reached.sum()) for p in paths] == list(reaches)
    for path, task in zip(paths, config.tasks):
        route, _ = tasks.zigzag_route(config, task)
        first_trial = path.k[:int(np.argmax(path.breaks)) + 1]
        changes = first_trial[np.r_[True, first_trial[1:] != first_trial[:-1]]]
        assert tuple(changes) == route  # one colour per edge of the route, in order
        np.testing.assert_allclose(path.seen_pos[0], task.start)


def test_figures_are_returned_not_drawn_with_pyplot(tiny, tmp_path):
    from matplotlib.figure import Figure

    config = tiny("EE-LS")
    steps = 5
    record = dict(pos=np.tile(np.asarray(config.tasks[0].start), (steps, 1)), k=np.zeros(steps, int),
                  breaks=np.zeros(steps, bool))
    fig = arena_figures.plot_paths(config, [dict(name="row", tasks=[record] * 6, experts=["a", "b", "c"])], "title")
    assert isinstance(fig, Figure)
    labels = [t.get_text() for legend in fig.subfigs[0].legends for t in legend.get_texts()]
    assert labels == ["a", "b", "c", "start", "target"]
    fitness = charts.plot_fitness({"EE-LS": np.ones((2, 3)), "other": np.ones(3)})
    lines = fitness.axes[0].get_lines()
    assert [line.get_label() for line in lines] == ["EE-LS", "other"] and lines[0].get_color() == "0.55"
    path = plotting.save(fitness, str(tmp_path / "fitness.png"))
    assert os.listdir(tmp_path) == ["fitness.png"] and path.endswith("fitness.png")
    from PIL import Image

    finer = plotting.save(fitness, str(tmp_path / "new" / "fitness.png"), dpi=2 * plotting.DPI)  # its folder made
    assert Image.open(finer).size == tuple(2 * n for n in Image.open(path).size)


def test_a_long_title_is_wrapped_inside_the_figure():
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    title = "EE-LS: best fitness per generation, mean and std over 1 seed(s), reduced scale"
    fig = charts.plot_fitness({"EE-LS": np.ones((1, 2))}, title=title, ylabel="best fitness of the population")
    canvas = FigureCanvasAgg(fig)
    canvas.draw()
    text = fig.axes[0].title
    box = text.get_window_extent(canvas.get_renderer())
    assert text.get_text().replace("\n", " ") == title and "\n" in text.get_text()
    assert 0 <= box.x0 and box.x1 <= fig.bbox.width and box.y1 <= fig.bbox.height


def test_demo_writes_only_into_a_new_empty_or_own_directory(tiny, tmp_path, capsys):
    from imrl_jax.runs.rundir import RunDirError

    config = tiny("EE-LS")
    own = tmp_path / "demo"
    own.mkdir()
    for name in demo.OUTPUTS:
        (own / name).write_text("an earlier demo")
    with pytest.raises(RunDirError, match="already holds a demo output .pass --overwrite"):
        demo.run(config, str(own))
    assert (own / "summary.json").read_text() == "an earlier demo"
    demo.run(config, str(own), overwrite=True)
    assert json.loads((own / "summary.json").read_text())["condition"] == "EE-LS"
    user = tmp_path / "mine"
    user.mkdir()
    (user / "notes.txt").write_text("kept")
    assert demo.main(["--out", str(user), "--overwrite"]) == 2
    err = capsys.readouterr().err.strip()
    assert err == f"error: --out: {user} is not empty and holds no demo output (it holds notes.txt); choose a new or empty directory"
    assert os.listdir(user) == ["notes.txt"]
