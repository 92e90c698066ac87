"""Progress as one structured stream of events (imrl_jax.runs.events): the runner's file, and TensorBoard."""

import csv
import io
import json
import os
import struct

import numpy as np
import pytest
from helpers import evolve_args

from imrl_jax.runs import events
from imrl_jax.runs.progress import Progress


def test_the_reader_returns_each_event_once_and_waits_for_a_whole_line(tmp_path):
    path = tmp_path / "events"
    reader = events.Reader(str(path))
    assert reader.read() == []  # not written yet
    path.write_text('{"kind": "progress", "done": 1}\n{"kind": "no')
    assert reader.read() == [{"kind": "progress", "done": 1}]
    with open(path, "a") as f:
        f.write('te", "text": "t"}\nnot an event\n')
    assert reader.read() == [{"kind": "note", "text": "t"}] and reader.read() == []


def test_progress_writes_its_events_and_leaves_its_lines_to_a_runner_that_reads_them(tmp_path, monkeypatch):
    path = tmp_path / "events"
    stream = io.StringIO()
    log = events.EventLog([events.JsonLines(str(path))])
    progress = Progress(3, stream=stream, first_index=0, log=log)
    for done in (1, 2, 3):
        progress.update(done, best=done / 10, mean=done / 20, lane_steps_per_s=5e6)
    progress.note("a note")
    got = [json.loads(line) for line in path.read_text().splitlines()]
    assert [(e["kind"], e.get("index"), e.get("done"), e.get("total")) for e in got] == [
        ("progress", 0, 1, 3), ("progress", 1, 2, 3), ("progress", 2, 3, 3), ("note", None, None, None)]
    assert got[1]["best"] == 0.2 and got[1]["mean"] == 0.1 and got[1]["lane_steps_per_s"] == 5e6
    assert got[0]["lane_steps_per_s"] is None and got[0]["eta_s"] is None  # the first unit compiles
    assert got[2]["line"].startswith("gen 2 (3/3) | best 0.3000 mean 0.1500 | ") and got[3]["text"] == "a note"
    printed = stream.getvalue().splitlines()
    assert [line[:11] for line in printed] == ["gen 0 (1/3)", "gen 1 (2/3)", "gen 2 (3/3)", "a note"]  # printed too
    monkeypatch.setenv(events.ENV, str(path))
    stream = io.StringIO()
    Progress(2, stream=stream).update(1, 0.0, 0.0, 1.0)  # the file set by hand: the line is printed as ever
    assert stream.getvalue().startswith("gen 1 (1/2)")
    monkeypatch.setenv(events.READER, "1")
    stream = io.StringIO()
    progress = Progress(2, stream=stream)  # its log from the environment, as a stage's is
    progress.update(1, 0.0, 0.0, 1.0)
    progress.note("kept")
    assert stream.getvalue() == "kept\n" and json.loads(path.read_text().splitlines()[-1])["text"] == "kept"


def _scalars(folder) -> dict:
    """{tag: [(step, value)]} of the TensorBoard event files in ``folder`` (TFRecord framing, Event protos)."""
    from tensorboardX.proto import event_pb2

    found = {}
    for name in sorted(os.listdir(folder)):
        data = open(os.path.join(folder, name), "rb").read()
        at = 0
        while at < len(data):
            length = struct.unpack("<Q", data[at:at + 8])[0]
            event = event_pb2.Event.FromString(data[at + 12:at + 12 + length])
            at += 12 + length + 4
            for value in event.summary.value:
                found.setdefault(value.tag, []).append((event.step, value.simple_value))
    return found


def test_evolve_writes_its_progress_for_tensorboard(tmp_path):
    pytest.importorskip("tensorboardX")
    from imrl_jax.commands import evolve

    out = tmp_path / "run"
    args = evolve_args(seeds=2, population=4, parents=2, generations=2, task_steps=200, bins=1)
    assert evolve.main([*args, "--set", "target_radius=40", "--out", str(out), "--log", "tensorboard"]) == 0
    scalars = _scalars(out / "tensorboard")
    with open(out / "history.csv") as f:
        rows = list(csv.DictReader(f))
    best = [max(float(r["best"]) for r in rows if int(r["generation"]) == g) for g in (0, 1)]
    assert [step for step, _ in scalars["fitness/best"]] == [0, 1]
    np.testing.assert_allclose([v for _, v in scalars["fitness/best"]], best, rtol=1e-6)
    assert [step for step, _ in scalars["speed/lane_steps_per_s"]] == [1]  # generation 0 compiles: no rate
    assert "fitness/mean" in scalars


def test_a_log_that_cannot_be_written_is_refused_before_anything_is(tmp_path, capsys):
    from imrl_jax.commands import evolve

    out = tmp_path / "run"
    assert evolve.main([*evolve_args(generations=1), "--out", str(out), "--log", "wandb"]) == 2
    assert capsys.readouterr().err == "error: --log: unknown log 'wandb' (choose from tensorboard)\n"
    assert not out.exists()


def _shown(folder, tag="fitness/best") -> list[int]:
    """The steps of ``tag`` TensorBoard shows from the event files in ``folder``: a writer's purge (a session START at
    step s) hides what earlier writers wrote from step s on."""
    from tensorboardX.proto import event_pb2

    events_seen = []
    for name in os.listdir(folder):
        data = open(os.path.join(folder, name), "rb").read()
        at = 0
        while at < len(data):
            length = struct.unpack("<Q", data[at:at + 8])[0]
            events_seen.append(event_pb2.Event.FromString(data[at + 12:at + 12 + length]))
            at += 12 + length + 4
    steps = []
    for event in sorted(events_seen, key=lambda e: e.wall_time):
        if event.HasField("session_log") and event.session_log.status == event_pb2.SessionLog.START:
            steps = [s for s in steps if s < event.step]
        steps += [event.step for value in event.summary.value if value.tag == tag]
    return steps


def test_a_resumed_run_does_not_show_its_redone_generations_twice_in_tensorboard(tmp_path):
    """Resumed from an older checkpoint, a run wrote again the steps of the generations it redid."""
    pytest.importorskip("tensorboardX")
    import shutil

    from imrl_jax.commands import evolve

    out = tmp_path / "run"
    args = evolve_args(seeds=1, population=4, parents=2, generations=2, task_steps=200, bins=1)
    assert evolve.main([*args, "--out", str(out), "--log", "tensorboard"]) == 0
    assert _shown(out / "tensorboard") == [0, 1]
    shutil.rmtree(out / "checkpoints" / "2")  # killed while saving generation 1: it is redone
    assert evolve.main(["--resume", "--out", str(out), "--log", "tensorboard", "--quiet"]) == 0
    assert len(os.listdir(out / "tensorboard")) == 2 and _shown(out / "tensorboard") == [0, 1]
