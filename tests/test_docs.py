"""Every relative link in README.md and docs/*.md points at something that exists in a clone."""

import glob
import os
import re

import pytest

from helpers import ROOT

LINK = re.compile(r"!?\[[^\]]*\]\(\s*<?([^)\s>]+)>?(?:\s+\"[^\"]*\")?\s*\)")
FENCE = re.compile(r"^(```|~~~).*?^\1", re.S | re.M)
DOCUMENTS = ["README.md", *sorted(os.path.relpath(p, ROOT) for p in glob.glob(os.path.join(ROOT, "docs", "*.md")))]


def broken_links(path: str) -> list[str]:
    """The relative link targets of a markdown file (code blocks left out) that do not exist."""
    with open(path) as f:
        text = FENCE.sub("", f.read())
    broken = []
    for target in LINK.findall(text):
        if re.match(r"[a-z][a-z0-9+.-]*:", target, re.I) or target.startswith("#"):
            continue  # a URL, a mail address or an anchor in the same page
        local = target.split("#")[0].split("?")[0]
        if not os.path.exists(os.path.join(os.path.dirname(path), local)):
            broken.append(target)
    return broken


@pytest.mark.parametrize("document", DOCUMENTS)
def test_relative_links_resolve(document):
    assert broken_links(os.path.join(ROOT, document)) == []


def test_a_broken_link_is_found(tmp_path):
    (tmp_path / "there.md").write_text("")
    page = tmp_path / "page.md"
    page.write_text("[ok](there.md#top) [web](https://example.org) [gone](docs/GONE.md) ![pic](img/x.png)\n"
                    "```\n[in code](nowhere.md)\n```\n")
    assert broken_links(str(page)) == ["docs/GONE.md", "img/x.png"]


def test_the_floors_make_test_min_installs_are_the_declared_ones():
    import tomllib

    with open(os.path.join(ROOT, "pyproject.toml"), "rb") as f:
        declared = dict(re.fullmatch(r"([\w-]+)>=([\d.]+)", d).groups() for d in tomllib.load(f)["project"]["dependencies"])
    with open(os.path.join(ROOT, "tests", "floors.txt")) as f:
        pinned = dict(line.strip().split("==") for line in f if line.strip() and not line.startswith("#"))
    from packaging.version import Version  # 1.26 is 1.26.0

    assert {name: Version(v) for name, v in declared.items()} == {
        name: Version(v) for name, v in pinned.items() if name != "jaxlib"}
    assert pinned["jaxlib"] == pinned["jax"]


def test_model_md_gives_every_bound_of_the_config():
    """docs/MODEL.md's "Bounds of the settings" has a row per bounded field with its bounds and derived check."""
    from imrl_jax.config import DERIVED_BOUNDS, bounds

    with open(os.path.join(ROOT, "docs", "MODEL.md")) as f:
        text = f.read()
    for name, bound in bounds().items():
        assert f"| `{name}` | {bound} | {DERIVED_BOUNDS.get(name, '')} |".replace("|  |", "| |") in text, name
    for name in set(DERIVED_BOUNDS) - set(bounds()):
        assert f"| `{name}` | | {DERIVED_BOUNDS[name]} |" in text, name


def test_the_readmes_library_examples_run():
    """Its python blocks, in order, in one namespace (at a shorter length): the environment example once passed the
    learning values where the task goes, which failed deep inside (AttributeError ... 'target')."""
    with open(os.path.join(ROOT, "README.md")) as f:
        blocks = re.findall(r"^```python\n(.*?)^```", f.read(), re.S | re.M)
    code = "\n".join(blocks)
    assert "task_steps=10_000" in code and "(50, config.num_genes)" in code and "env.step(" in code
    code = code.replace("task_steps=10_000", "task_steps=100, num_bins=1").replace("(50, config.num_genes)",
                                                                                 "(2, config.num_genes)")
    namespace = {}
    exec(compile(code, "README.md", "exec"), namespace)  # noqa: S102 - the project's own README
    assert namespace["result"].fitness.shape == (2,) and namespace["x"].shape == (36,)
    assert not bool(namespace["events"].reached)


def test_the_readme_names_every_condition_and_types_commands_one_way():
    """The README's --cond paragraph names every row of the condition table (evolved or not), and its commands are
    typed in the environment make creates (.venv/bin/python), never a bare python that only an activated one runs."""
    from imrl_jax import conditions

    with open(os.path.join(ROOT, "README.md")) as f:
        readme = f.read()
    paragraph = readme[readme.index("`--cond` is an evolved condition"):].split("\n\n")[0]
    missing = [name for name in conditions.CONDITIONS if not re.search(rf"(?<![\w-]){re.escape(name)}(?![\w-])",
                                                                       paragraph)]
    assert not missing, f"README's --cond paragraph lacks {missing}"
    bare = [line for line in readme.splitlines()
            if re.search(r"(?<![/\w.])python3? -m (imrl_jax|experiments)", line) and "PYTHONPATH=." not in line]
    assert not bare, bare
