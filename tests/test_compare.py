"""The in-process speed comparison of two revisions: export, input checks, one tiny comparison."""

import os
import re

import pytest

from imrl_jax.commands import compare


def test_export_renames_every_import(tmp_path):
    target = compare.export_package("HEAD", "imrl_old", str(tmp_path))
    lifetime = os.path.join(target, "agent", "lifetime.py")
    assert os.path.isfile(lifetime)
    for folder, _, files in os.walk(target):
        for file in files:
            if file.endswith(".py"):
                text = open(os.path.join(folder, file)).read()
                assert not re.search(r"^\s*(from|import) imrl_jax\b", text, re.MULTILINE), file
    assert "from imrl_old.world.arena import" in open(lifetime).read()


def test_export_of_an_unknown_revision_names_it(tmp_path):
    with pytest.raises(ValueError, match="REV: .*'no-such-revision'"):
        compare.export_package("no-such-revision", "imrl_old", str(tmp_path))


@pytest.mark.parametrize("argv, field", [
    (["no-such-revision"], "REV"),
    (["HEAD", "--pairs", "0"], "--pairs"),
    (["HEAD", "--lanes", "0"], "--lanes"),
    (["HEAD", "--phase", "life", "--steps", "15"], "--steps"),
    (["HEAD", "--cpu-devices", "100000"], "--cpu-devices: 100,000 is above the limit"),
])
def test_bad_input_exits_2_naming_the_field(argv, field, capsys):
    assert compare.main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith(f"error: {field}") and "\n" not in err


def test_a_revision_against_this_checkout():
    lines = []
    result = compare.compare("HEAD", "adult", lanes=2, steps=20, pairs=2, log=lines.append)
    assert result["base_lane_steps_per_s"] > 0 and result["lane_steps_per_s"] > 0
    assert 0 <= result["pairs_won"] <= 2 and result["median_ratio"] > 0
    assert len(lines) == 2 and lines[-1].startswith("pair 2/2")
