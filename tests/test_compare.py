"""The in-process speed comparison of two revisions: export, input checks, one tiny comparison."""

import os
import re
import subprocess

import pytest

from imrl_jax.commands import bench, compare


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


@pytest.mark.parametrize("layout", ["flat", "layers"])
def test_a_revision_s_modules_are_found_in_either_layout(tmp_path, monkeypatch, layout):
    """Revisions before the sub-packages kept lifetime.py beside config.py; later ones in agent/."""
    package = tmp_path / f"imrl_{layout}"
    folder = package / "agent" if layout == "layers" else package
    folder.mkdir(parents=True)
    for path in {package, folder}:
        (path / "__init__.py").write_text("")
    (package / "config.py").write_text("WHERE = 'top'\n")
    (folder / "lifetime.py").write_text(f"WHERE = {layout!r}\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    assert bench._module(package.name, "lifetime").WHERE == layout
    assert bench._module(package.name, "config").WHERE == "top"
    with pytest.raises(ModuleNotFoundError, match="has no module networks"):
        bench._module(package.name, "networks")


@pytest.mark.slow
def test_a_revision_before_the_layers_against_this_checkout():
    """The last revision of one flat folder (the bench builds its program from either layout)."""
    before = "83834b5"
    if subprocess.run(["git", "-C", compare.REPO, "cat-file", "-e", f"{before}^{{commit}}"]).returncode:
        pytest.skip(f"{before} is not in this clone's history")
    result = compare.compare(before, "childhood", lanes=2, steps=20, pairs=1, log=lambda line: None)
    assert result["base_lane_steps_per_s"] > 0 and result["lane_steps_per_s"] > 0
