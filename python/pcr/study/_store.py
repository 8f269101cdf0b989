"""A study's results on disk: a Parquet dataset, one file per flush of finished trials, next to
the study's definition (``_study.json``; Parquet readers skip names that start with '_' or '.').

Each file is written under a hidden temporary name and renamed into place, so a study stopped
at any point leaves only whole files; resuming skips the trials they hold.
"""
from __future__ import annotations

import hashlib
import json
import os
import uuid

import pyarrow as pa
import pyarrow.parquet as pq

from .._files import write_atomically
from ._definition import Study
from ._trial import FACTORS

MANIFEST = "_study.json"
_KEYS = [("trial", pa.int64()), ("replicate", pa.int64()), ("seed", pa.int64())]
_ARROW = {str: pa.string(), float: pa.float64(), int: pa.int64()}


def _digests(robots):
    return {name: hashlib.sha256(text.encode()).hexdigest() for name, text in robots.items()}


def schema(outcomes):
    """The columns of a study's table: trial, replicate, seed, every factor, the outcomes (float64,
    SI) and failure (null when the trial succeeded)."""
    fields = [pa.field(n, t) for n, t in _KEYS]
    fields += [pa.field(name, _ARROW[f.kind]) for name, f in FACTORS.items()]
    fields += [pa.field(name, pa.float64()) for name in outcomes]
    fields.append(pa.field("failure", pa.string()))
    return pa.schema(fields)


class ResultStore:
    """The directory of a study's results: created for a new study, reopened to resume one."""

    def __init__(self, directory, study, outcomes, robots):
        """robots: the robot JSON texts the study's trials use, by name: a study resumed with a
        robot file that changed since is refused."""
        self.directory = os.fspath(directory)
        self.schema = schema(outcomes)
        manifest = os.path.join(self.directory, MANIFEST)
        if os.path.lexists(self.directory) and not os.path.isdir(self.directory):
            raise NotADirectoryError(f"{self.directory}: exists and is not a directory")
        if os.path.isdir(self.directory) and os.listdir(self.directory):
            if not os.path.isfile(manifest):
                raise FileExistsError(f"{self.directory}: not empty and holds no study "
                                      f"({MANIFEST}); give a new or empty directory")
            with open(manifest) as f:
                stored = json.load(f)
            if stored.get("robots") != _digests(robots):
                raise ValueError(f"{manifest}: the study's robot files changed since its results "
                                 "were written; give a new directory to run it again")
            if stored.get("study") != study.identity() or stored.get("columns") != list(outcomes):
                raise ValueError(
                    f"{manifest}: holds the results of another study (or another version of "
                    f"it): {json.dumps(stored.get('study'))}; give a new directory to run "
                    f"{study.name!r}")
        else:
            os.makedirs(self.directory, exist_ok=True)
            text = json.dumps({"study": study.identity(), "columns": list(outcomes),
                               "robots": _digests(robots), "definition": study.to_dict()},
                              indent=2) + "\n"
            write_atomically(manifest, text.encode())

    def parts(self):
        return sorted(os.path.join(self.directory, n) for n in os.listdir(self.directory)
                      if n.startswith("part-") and n.endswith(".parquet"))

    def done(self):
        """The indices of the trials already written."""
        out = set()
        for part in self.parts():
            out.update(pq.read_table(part, columns=["trial"]).column("trial").to_pylist())
        return out

    def write(self, rows):
        """Writes finished trials' rows (dicts over the schema's columns) as one new file."""
        if not rows:
            return
        columns = {name: [r.get(name) for r in rows] for name in self.schema.names}
        table = pa.table(columns, schema=self.schema)
        sink = pa.BufferOutputStream()
        pq.write_table(table, sink, compression="zstd")
        name = f"part-{min(r['trial'] for r in rows):07d}-{uuid.uuid4().hex[:8]}.parquet"
        write_atomically(os.path.join(self.directory, name), sink.getvalue().to_pybytes())


def read_results(directory):
    """A study's table (pandas DataFrame), one row per finished trial in trial order."""
    directory = os.fspath(directory)
    manifest = os.path.join(directory, MANIFEST)
    if not os.path.isfile(manifest):
        raise FileNotFoundError(f"{directory}: no study results here (no {MANIFEST})")
    with open(manifest) as f:
        columns = json.load(f)["columns"]
    parts = [os.path.join(directory, n) for n in sorted(os.listdir(directory))
             if n.startswith("part-") and n.endswith(".parquet")]
    if not parts:
        return schema(columns).empty_table().to_pandas()
    table = pa.concat_tables(pq.read_table(p, schema=schema(columns)) for p in parts)
    frame = table.to_pandas()
    frame = frame.drop_duplicates("trial").sort_values("trial", kind="stable")
    return frame.reset_index(drop=True)


def read_study(directory):
    """The Study whose results `directory` holds."""
    with open(os.path.join(os.fspath(directory), MANIFEST)) as f:
        return Study.from_dict(json.load(f)["definition"], os.path.join(directory, MANIFEST))
