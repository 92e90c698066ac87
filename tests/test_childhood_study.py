"""The childhood study's command refuses bad input in one line, exit 2, writing nothing."""

import pytest

from experiments import childhood_study


@pytest.mark.parametrize("argv, field", [
    (["hand", "--rules", "bogus"], "--rules"),
    (["hand", "--walls", "bounce", "--lengths", "300", "--seeds", "1"], "childhood_walls"),
    (["evolve", "--runs", "nope"], "--runs"),
    (["evolved", "/nonexistent/run"], "not a run directory"),
])
def test_bad_input_exits_2_naming_it(tmp_path, capsys, monkeypatch, argv, field):
    monkeypatch.setattr("imrl_jax.devices.use_host_cores", lambda count=None: None)  # leave the suite's devices
    out = tmp_path / "study"
    try:
        code = childhood_study.main(argv + ["--out", str(out)])
    except SystemExit as exit_:  # argparse's error
        code = exit_.code
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and field in err[-1]
    assert not out.exists()
