"""The documentation names what the tools take and what they write.

Every long option that `pcr SUBCOMMAND --help` (for each subcommand `pcr --help` lists) and
`pcr_calibrate --help` print must appear in README.md or docs/*.md, and every column of the CSV
files the tools write must appear in docs/formats.md, inside a code span (`name`, or a list such
as `q1,...,qn,x,y,theta`). Each run below is small: the whole file takes a few seconds. The
relative links between the pages must lead to a file and, with a #fragment, to a heading of it.
"""
import functools
import glob
import os
import re
import subprocess

import pytest

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
FORMATS = os.path.join(ROOT, "docs", "formats.md")

# An option line of CLI11's help: "  --robot TEXT ..." or "  -h,--help ...".
OPTION_LINE = re.compile(r"^\s+(?:-\w,)?(--[A-Za-z0-9][\w-]*)")
COMMON_OPTIONS = {"--help"}  # every command has it


def _read(path):
    with open(path, encoding="utf-8") as f:
        return f.read()


def _docs_text():
    paths = [os.path.join(ROOT, "README.md")]
    paths += sorted(glob.glob(os.path.join(ROOT, "docs", "*.md")))
    return "\n".join(_read(p) for p in paths)


def _documented_names():
    """The identifiers inside the code spans of docs/formats.md (fenced blocks included)."""
    text = _read(FORMATS)
    spans = re.findall(r"```.*?```", text, flags=re.S)
    spans += re.findall(r"`([^`\n]+)`", re.sub(r"```.*?```", "", text, flags=re.S))
    names = set()
    for span in spans:
        names.update(re.findall(r"[A-Za-z_][A-Za-z0-9_]*", span))
    return names


def _run(args, cwd, stdin=None):
    result = subprocess.run(args, cwd=cwd, input=stdin, capture_output=True, text=True,
                            timeout=120)
    assert result.returncode == 0, (f"{' '.join(map(str, args))} exited with "
                                    f"{result.returncode}:\n{result.stderr}")
    return result.stdout


@functools.lru_cache(maxsize=None)
def _subcommands(cli):
    text = _run([cli, "--help"], cwd=ROOT)
    names = []
    in_list = False
    for line in text.splitlines():
        if line.startswith("Subcommands:"):
            in_list = True
        elif in_list and re.match(r"^  \S", line):
            names.append(line.split()[0])
        elif in_list and line.strip() and not line.startswith(" "):
            in_list = False
    assert names, f"no subcommands in `pcr --help`:\n{text}"
    return tuple(names)


def _long_options(help_text):
    options = []
    for line in help_text.splitlines():
        match = OPTION_LINE.match(line)
        if match and match.group(1) not in COMMON_OPTIONS and match.group(1) not in options:
            options.append(match.group(1))
    return options


def _mentioned(option, text):
    return re.search(re.escape(option) + r"(?![\w-])", text) is not None


def _calibrate_tool(cli):
    path = os.path.join(os.path.dirname(os.path.abspath(cli)), "pcr_calibrate")
    return path if os.access(path, os.X_OK) else None


def test_every_option_of_pcr_is_documented(cli):
    docs = _docs_text()
    missing = []
    for command in _subcommands(cli):
        for option in _long_options(_run([cli, command, "--help"], cwd=ROOT)):
            if not _mentioned(option, docs):
                missing.append(f"pcr {command} {option}")
    assert not missing, "options not documented in README.md or docs/*.md: " + ", ".join(missing)


def test_every_option_of_pcr_calibrate_is_documented(cli):
    tool = _calibrate_tool(cli)
    if tool is None:
        pytest.skip("pcr_calibrate is not built next to pcr")
    docs = _docs_text()
    options = _long_options(_run([tool, "--help"], cwd=ROOT))
    assert options, "no options in `pcr_calibrate --help`"
    missing = [o for o in options if not _mentioned(o, docs)]
    assert not missing, ("pcr_calibrate options not documented in README.md or docs/*.md: " +
                         ", ".join(missing))


def _header(text):
    """The first line that is not a `#` comment, split into column names."""
    for line in text.splitlines():
        if line.strip() and not line.startswith("#"):
            return line.strip().split(",")
    raise AssertionError(f"no header in:\n{text[:500]}")


def _header_of(path):
    return _header(_read(path))


# Each producer runs one cheap command in `tmp` and returns {what: header}. The joints q1..qn are
# documented as `q1`...`qn`, so a column qK counts as q1.
def _fk(cli, tmp):
    out = _run([cli, "fk"], cwd=tmp, stdin="q1,q2,q3\n0,0,0\n0.001,0,-0.001\n")
    return {"pcr fk (stdout)": _header(out)}


def _ik(cli, tmp):
    fk = _run([cli, "fk"], cwd=tmp, stdin="q1,q2,q3\n0.001,0,-0.001\n").splitlines()
    row = dict(zip(fk[0].split(","), fk[1].split(",")))
    pose = f"x,y,theta\n{row['x']},{row['y']},{row['theta']}\n"
    return {"pcr ik (stdout)": _header(_run([cli, "ik"], cwd=tmp, stdin=pose))}


def _workspace(cli, tmp):
    _run([cli, "workspace", "--samples", "3", "--output", "workspace.csv"], cwd=tmp)
    return {"pcr workspace --output": _header_of(os.path.join(tmp, "workspace.csv"))}


def _sample(cli, tmp):
    _run([cli, "sample", "--count", "3", "--validation-count", "2", "--output", "q.csv",
          "--validation-output", "v.csv"], cwd=tmp)
    return {"pcr sample --output": _header_of(os.path.join(tmp, "q.csv")),
            "pcr sample --validation-output": _header_of(os.path.join(tmp, "v.csv"))}


def _simulate(cli, tmp):
    _run([cli, "sample", "--count", "3", "--output", "q.csv"], cwd=tmp)
    _run([cli, "simulate", "--configs", "q.csv", "--output", "data.csv", "--truth", "t.json"],
         cwd=tmp)
    return {"pcr simulate --output": _header_of(os.path.join(tmp, "data.csv"))}


def _sensitivity(cli, tmp):
    _run([cli, "sensitivity", "--csv", "sensitivity.csv"], cwd=tmp)
    return {"pcr sensitivity --csv": _header_of(os.path.join(tmp, "sensitivity.csv"))}


def _map(cli, tmp):
    _run([cli, "map", "--grid", "3", "--output", "map.csv"], cwd=tmp)
    rotation = _run([cli, "map", "--rotation-range", "0,0"], cwd=tmp)
    return {"pcr map --output": _header_of(os.path.join(tmp, "map.csv")),
            "pcr map --rotation-range": _header(rotation)}


def _accuracy(cli, tmp):
    _run([cli, "accuracy", "--count", "4", "--repeat", "2", "--format", "csv", "--output",
          "accuracy.csv", "--poses", "poses.csv"], cwd=tmp)
    return {"pcr accuracy --format csv": _header_of(os.path.join(tmp, "accuracy.csv")),
            "pcr accuracy --poses": _header_of(os.path.join(tmp, "poses.csv"))}


def _calibrate(cli, tmp):
    tool = _calibrate_tool(cli)
    if tool is None:
        pytest.skip("pcr_calibrate is not built next to pcr")
    # 12 configurations: the default robot's last stage frees 33 parameters, 3 per row.
    _run([cli, "sample", "--count", "12", "--output", "q.csv"], cwd=tmp)
    _run([cli, "simulate", "--configs", "q.csv", "--output", "data.csv"], cwd=tmp)
    _run([tool, "--robot", os.path.join(ROOT, "robots", "femto-3pf.json"), "--data", "data.csv",
          "--output", "identified.json", "--residuals", "residuals.csv", "--quiet"], cwd=tmp)
    return {"pcr_calibrate --residuals": _header_of(os.path.join(tmp, "residuals.csv"))}


PRODUCERS = {  # the subcommand each needs, and the producer
    "fk": ("fk", _fk),
    "ik": ("ik", _ik),
    "workspace": ("workspace", _workspace),
    "sample": ("sample", _sample),
    "simulate": ("simulate", _simulate),
    "sensitivity": ("sensitivity", _sensitivity),
    "map": ("map", _map),
    "accuracy": ("accuracy", _accuracy),
    "pcr_calibrate": ("simulate", _calibrate),
}


@pytest.mark.parametrize("name", list(PRODUCERS))
def test_every_column_written_is_in_the_formats_page(cli, tmp_path, name):
    command, producer = PRODUCERS[name]
    if command not in _subcommands(cli):
        pytest.skip(f"pcr {command} is not built")
    documented = _documented_names()
    missing = []
    for what, header in producer(cli, str(tmp_path)).items():
        assert header, f"{what}: an empty header"
        for column in header:
            key = "q1" if re.fullmatch(r"q[0-9]+", column) else column
            if key not in documented:
                missing.append(f"{what}: {column}")
    assert not missing, "columns not documented in docs/formats.md: " + ", ".join(missing)


def _slugs(path):
    """The anchors of a Markdown file's headings, as GitHub makes them."""
    text = re.sub(r"^```.*?^```", "", _read(path), flags=re.S | re.M)
    seen = {}
    slugs = set()
    for line in text.splitlines():
        match = re.match(r"^#{1,6}\s+(.*?)\s*$", line)
        if match:
            slug = re.sub(r"[^\w\- ]", "", match.group(1).strip().lower()).replace(" ", "-")
            slugs.add(slug if slug not in seen else f"{slug}-{seen[slug]}")
            seen[slug] = seen.get(slug, 0) + 1
    return slugs


def test_relative_links_resolve():
    pages = [os.path.join(ROOT, "README.md"), os.path.join(ROOT, "python", "README.md")]
    pages += sorted(glob.glob(os.path.join(ROOT, "docs", "*.md")))
    broken = []
    for page in pages:
        text = re.sub(r"^```.*?^```", "", _read(page), flags=re.S | re.M)
        text = re.sub(r"`[^`\n]*`", "", text)
        for target in re.findall(r"\[[^\]]*\]\(([^)\s]+)\)", text):
            if re.match(r"[a-z]+:", target):  # https:, mailto:
                continue
            path, _, fragment = target.partition("#")
            dest = os.path.normpath(os.path.join(os.path.dirname(page), path)) if path else page
            if not os.path.exists(dest) or (fragment and fragment not in _slugs(dest)):
                broken.append(f"{os.path.relpath(page, ROOT)}: {target}")
    assert not broken, "links that lead nowhere: " + ", ".join(broken)
