"""A run named by what it computes: an evolution's spec, its content key, and where its directory is.

Two evolutions that live the same lives (the same model, seeds and search) are one run, however a
study came to ask for it. The model is the config less the fields its condition never reads
(``Condition.ignored_fields``, tested against the NumPy reference) and the compute choices
(``config.COMPUTE_FIELDS``); so a run's **key** is a hash of those fields, its seeds and its search
(strategy and settings). ``num_generations`` is left out as well: a run's length is how far it has
come, not which run it is (``evolve --resume --generations N`` extends it).

Every committed run directory keeps its place: :func:`index` reads the ``config.json`` of every
run under a results folder and maps its key to its directory, so a study finds a finished run by
its key wherever it lies, and a new one goes to ``runs/KEY`` (:func:`locate`). The keys of the
committed runs are recorded in ``experiments/results/run_keys.json`` and a test holds them fixed:
a change of the key that would orphan a committed run fails it.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import os
from typing import Iterable

from imrl_jax.config import COMPUTE_FIELDS, WORLD_FIELDS, Config, ConfigError
from imrl_jax.runs.rundir import RunDirError, read_json

#: The search a run records when it records none: the paper's GA (``strategies.GA_RECORD``).
GA_SEARCH = {"strategy": "ga", "settings": {}}
#: Hex digits of a key (64 bits: no two of a project's runs meet by chance).
KEY_LENGTH = 16
#: Fields that are no part of a run's identity whatever the condition (see the module's docstring).
PROGRESS_FIELDS = ("num_generations",)


def canonical(value) -> str:
    """``value`` (JSON-like) as canonical JSON: sorted keys, no spaces, every number a float (so 12 and 12.0,
    one value, are one text; -0 is 0)."""
    plain = json.loads(json.dumps(value), parse_int=float, parse_float=lambda text: float(text) + 0.0)  # -0.0 + 0 is 0.0
    return json.dumps(plain, sort_keys=True, separators=(",", ":"))


class DuplicateRunError(RunDirError):
    """Two run directories hold the same run (the same key)."""


def model(config: Config) -> dict:
    """A config's model: its fields less the compute choices, the run's length and those its condition never reads
    (and, in the arena, the fields of other worlds)."""
    skip = set(COMPUTE_FIELDS) | set(PROGRESS_FIELDS) | config.spec.ignored_fields()
    if config.world == "arena":
        skip |= set(WORLD_FIELDS)
    return {k: v for k, v in config.to_dict().items() if k not in skip}


def _hash(identity: dict) -> str:
    return hashlib.sha256(canonical(identity).encode()).hexdigest()[:KEY_LENGTH]


@dataclasses.dataclass(frozen=True)
class RunSpec:
    """An evolution as what it computes: its config, its seeds and its search (strategy, settings)."""

    config: Config
    seeds: tuple[int, ...]
    search: str = canonical(GA_SEARCH)  # the config.json ``search`` record, as canonical JSON

    @classmethod
    def make(cls, config: Config, seeds: Iterable[int], search: dict | None = None) -> "RunSpec":
        """A spec from a config, seeds and a config.json-style search record (None: the paper's GA)."""
        return cls(config, tuple(int(s) for s in seeds), canonical(GA_SEARCH if search is None else search))

    @classmethod
    def from_run_dir(cls, run_dir: str) -> "RunSpec":
        """The spec a run directory's ``config.json`` records (raises RunDirError naming the file)."""
        from imrl_jax.runs.rundir import read_config

        config, seeds = read_config(run_dir)
        path = os.path.join(run_dir, "config.json")
        try:
            with open(path) as f:
                search = json.load(f).get("search")
        except (OSError, ValueError) as error:
            raise RunDirError(f"{path} is unreadable ({error})") from None
        return cls.make(config, seeds, search)

    def identity(self) -> dict:
        """What the key is made of: the model's fields, the seeds and the search, as plain JSON values."""
        return {"model": model(self.config), "seeds": list(self.seeds), "search": json.loads(self.search)}

    def key(self) -> str:
        """The run's content key: a hash of :meth:`identity` in canonical JSON (:func:`canonical`)."""
        # Kept on the instance: a study's plan asks a row's (memoised) spec for its key many times.
        if "_key" not in self.__dict__:
            object.__setattr__(self, "_key", _hash(self.identity()))
        return self.__dict__["_key"]


def _walk(root: str, name: str):
    """Every folder under ``root`` holding a file ``name`` (a path within it), in order; a run's checkpoints, a
    test's partial runs and a landscape measure's replay of a few generations of one seed (a means, not a run)
    left out."""
    for folder, subfolders, files in os.walk(root):
        subfolders[:] = sorted(d for d in subfolders if d not in ("checkpoints", "resume_checkpoint", "partial")
                               and not d.startswith("landscape_replay"))
        if os.path.isfile(os.path.join(folder, name)):
            yield folder


def run_dirs(root: str) -> list[str]:
    """Every evolution's directory under ``root`` (one holding a ``config.json``), sorted, relative to ``root``."""
    return sorted(os.path.relpath(folder, root) for folder in _walk(root, "config.json"))


def index(root: str) -> dict[str, str]:
    """``{key: directory relative to root}`` of every run under ``root``; two directories of one run are an error."""
    keys: dict[str, str] = {}
    for folder in run_dirs(root):
        key = RunSpec.from_run_dir(os.path.join(root, folder)).key()
        if key in keys:
            raise DuplicateRunError(f"{os.path.join(root, folder)} and {os.path.join(root, keys[key])} hold the "
                                    f"same run (key {key})")
        keys[key] = folder
    return keys


def locate(root: str, spec: RunSpec, known: dict[str, str] | None = None) -> tuple[str, bool]:
    """Where ``spec``'s run lies under ``root``, and whether it exists: the directory that holds it, or
    ``root/runs/KEY/evolve`` for a new one (its learning tests go beside, in ``test``). ``known``: an
    :func:`index` of ``root`` already read."""
    key = spec.key()
    known = index(root) if known is None else known
    if key in known:
        return os.path.join(root, known[key]), True
    return os.path.join(root, "runs", key, "evolve"), False


#: What a learning test from scratch is besides its config: its sizes and its keys' seed (steady.json's names).
TEST_SIZES = ("num_runs", "num_best", "num_tests", "steady_steps", "seed")


def test_key(config: Config, sizes: dict) -> str:
    """The content key of a learning test from scratch (a condition that is not evolved): its model, as a run's,
    and its sizes (:data:`TEST_SIZES`)."""
    return _hash({"model": model(config), "sizes": {name: sizes[name] for name in TEST_SIZES}})


def test_index(root: str) -> dict[str, str]:
    """``{key: directory relative to root}`` of every learning test from scratch under ``root``: finished (a
    ``steady.json`` of a condition that is not evolved) or begun (its ``partial/spec.json`` records its key, so
    that a second study asking for it goes on with it, once the process testing it, which holds its lock, has
    stopped); two directories of one test, or an unreadable one, are an error (RunDirError naming the file)."""
    from imrl_jax import conditions

    keys: dict[str, str] = {}
    for folder in _walk(root, "steady.json"):
        path = os.path.join(folder, "steady.json")
        steady = read_json(path, "")
        config = steady.get("config") if isinstance(steady, dict) else None
        condition = conditions.CONDITIONS.get(config.get("condition")) if isinstance(config, dict) else None
        if condition is None or condition.evolved or any(name not in steady for name in TEST_SIZES):
            continue  # a test of evolved genomes is found beside its run; one without its sizes is no test of ours
        try:
            key = test_key(Config.from_dict(steady["config"]), steady)
        except ConfigError as error:
            raise RunDirError(f"{path} is unreadable ({error})") from None
        if key in keys:
            raise DuplicateRunError(f"{folder} and {os.path.join(root, keys[key])} hold the same learning test (key "
                                    f"{key})")
        keys[key] = os.path.relpath(folder, root)
    for folder in _walk(root, os.path.join("partial", "spec.json")):
        spec = read_json(os.path.join(folder, "partial", "spec.json"), "")
        key = spec.get("key") if isinstance(spec, dict) else None  # begun before tests recorded their key: not found
        if key is not None and os.path.relpath(folder, root) not in keys.values():
            if key in keys:
                raise DuplicateRunError(f"{folder} and {os.path.join(root, keys[key])} hold the same learning test "
                                        f"(key {key})")
            keys[key] = os.path.relpath(folder, root)
    return keys
