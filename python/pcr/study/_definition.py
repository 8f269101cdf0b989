"""A study's definition: fixed factors, the levels of the varied ones, the number of trials per
combination of levels and a seed; read from TOML (a file, or a built-in study's name)."""
from __future__ import annotations

import itertools
import json
import os
from dataclasses import dataclass, field
from importlib import resources

import numpy as np

from ._trial import BUILTIN_ROBOTS, check_factor

try:
    import tomllib as _toml
except ModuleNotFoundError:  # Python < 3.11: the [study] extra brings tomli
    import tomli as _toml

_TABLES = {"study": ("name", "description", "seed", "trials"), "factors": None, "levels": None}


def builtin_studies():
    """The names of the studies shipped with pcr (``pcr-study run NAME``)."""
    files = resources.files(__package__).joinpath("studies")
    return sorted(p.name[:-5] for p in files.iterdir() if p.name.endswith(".toml"))


@dataclass(frozen=True)
class Trial:
    """One trial: its index in the study, its replicate, its seed and its factors."""

    index: int
    replicate: int
    seed: int
    factors: dict


@dataclass(frozen=True)
class Study:
    """A table of trials: every combination of ``levels`` (factor -> list of values), each run
    ``trials`` times on top of the fixed ``factors``.

    Trial i is replicate i // C of combination i % C (C combinations, in the order of the levels'
    product), so that a study cut short, or extended with more trials, holds whole replicates of
    every combination. Its seed depends only on the study's seed and the replicate: the levels are
    compared on the same draws (common random numbers), and any trial is reproduced by
    ``run_trial(factors, seed)`` alone.
    """

    name: str
    description: str = ""
    seed: int = 1
    trials: int = 10
    factors: dict = field(default_factory=dict)
    levels: dict = field(default_factory=dict)

    @staticmethod
    def load(source):
        """A built-in study by name (``builtin_studies()``) or a TOML file's path."""
        if isinstance(source, str) and source in builtin_studies():
            text = resources.files(__package__).joinpath("studies", source + ".toml").read_text()
            return Study.from_toml(text, f"<built-in study {source}>")
        path = os.fspath(source)
        if not os.path.isfile(path):
            raise FileNotFoundError(
                f"{path}: no such study file (built-in studies: {', '.join(builtin_studies())})")
        with open(path, "rb") as f:
            data = f.read()
        try:
            text = data.decode("utf-8")
        except UnicodeDecodeError as e:
            raise ValueError(f"{path}: not UTF-8 text ({e})") from None
        study = Study.from_toml(text, path)
        # Robot files are named relative to the study file; built-in robots by their name.
        here = os.path.dirname(os.path.abspath(path))

        def located(robot):
            return robot if robot in BUILTIN_ROBOTS else os.path.join(here, robot)

        factors = dict(study.factors)
        if "robot" in factors:
            factors["robot"] = located(factors["robot"])
        levels = {k: ([located(v) for v in values] if k == "robot" else values)
                  for k, values in study.levels.items()}
        return study.replace(factors=factors, levels=levels)

    @staticmethod
    def from_toml(text, source="<string>"):
        try:
            data = _toml.loads(text)
        except _toml.TOMLDecodeError as e:
            raise ValueError(f"{source}: {e}") from None
        return Study.from_dict(data, source)

    @staticmethod
    def from_dict(data, source="<dict>"):
        """From {"study": {name, description, seed, trials}, "factors": {...}, "levels": {...}};
        ValueError naming the source, the field and the value for anything wrong."""
        for key, value in data.items():
            if key not in _TABLES:
                raise ValueError(f"{source}: unknown table [{key}] (expected [study], [factors], "
                                 "[levels])")
            if not isinstance(value, dict):
                raise ValueError(f"{source}: {key} must be a table")
        head = data.get("study", {})
        for key in head:
            if key not in _TABLES["study"]:
                raise ValueError(f"{source}: study.{key}: unknown field (expected "
                                 f"{', '.join(_TABLES['study'])})")
        name = head.get("name", os.path.splitext(os.path.basename(source))[0])
        if not isinstance(name, str) or not name:
            raise ValueError(f"{source}: study.name = {name!r}: expected a non-empty string")
        description = head.get("description", "")
        if not isinstance(description, str):
            raise ValueError(f"{source}: study.description: expected a string")
        seed, trials = head.get("seed", 1), head.get("trials", 10)
        for key, value, least in (("seed", seed, 0), ("trials", trials, 1)):
            if isinstance(value, bool) or not isinstance(value, int) or not least <= value < 2**63:
                raise ValueError(f"{source}: study.{key} = {value!r}: expected a whole number >= "
                                 f"{least}")
        factors = {k: check_factor(k, v, f"{source}: factors")
                   for k, v in data.get("factors", {}).items()}
        levels = {}
        for k, values in data.get("levels", {}).items():
            if not isinstance(values, list) or not values:
                raise ValueError(f"{source}: levels.{k} = {values!r}: expected a non-empty list")
            levels[k] = [check_factor(k, v, f"{source}: levels.{k}[{i}]")
                         for i, v in enumerate(values)]
            if len(set(levels[k])) != len(levels[k]):
                raise ValueError(f"{source}: levels.{k} = {values!r}: a level appears twice")
            if k in factors:
                raise ValueError(f"{source}: {k} is both a fixed factor and varied in [levels]")
        return Study(name, description, seed, trials, factors, levels)

    def to_dict(self):
        return {"study": {"name": self.name, "description": self.description, "seed": self.seed,
                          "trials": self.trials},
                "factors": dict(self.factors), "levels": {k: list(v) for k, v in
                                                          self.levels.items()}}

    def replace(self, **changes):
        d = {**self.__dict__, **changes}
        return Study(**d)

    def combinations(self):
        """The factors of each combination of levels, in trial order."""
        names = list(self.levels)
        return [{**self.factors, **dict(zip(names, values))}
                for values in itertools.product(*(self.levels[n] for n in names))]

    def trial_seed(self, replicate):
        state = np.random.SeedSequence([self.seed, replicate]).generate_state(1, dtype=np.uint64)
        return int(state[0] >> np.uint64(1))  # fits a signed 64-bit Parquet column

    def trial_list(self):
        """Every trial of the study, in index order."""
        combos = self.combinations()
        return [Trial(i, i // len(combos), self.trial_seed(i // len(combos)),
                      combos[i % len(combos)])
                for i in range(self.trials * len(combos))]

    def identity(self):
        """What must match for results to belong to this study: all but the number of trials."""
        d = self.to_dict()
        del d["study"]["trials"]
        return json.loads(json.dumps(d))  # tuples to lists, as read back from the manifest
