"""pcr-study: run and plot design and tolerance studies (``pcr-study --help``)."""
from __future__ import annotations

import argparse
import sys

_EPILOG = """\
examples:
  pcr-study run tolerance --output tolerance-results
  pcr-study run my-study.toml --output results --trials 200 --scheduler tcp://head:8786
  pcr-study plot tolerance-results
  pcr-study summary tolerance-results
A stopped study (Ctrl-C, a lost job) resumes where it stopped when run again into the same
directory. Units: SI in every file.
"""


def _positive(text):
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r}: expected a whole number") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"{text!r}: expected at least 1")
    return value


def _parser():
    p = argparse.ArgumentParser(
        prog="pcr-study", description="Monte Carlo studies over virtual planar parallel "
        "continuum robots: the whole method per trial, on Dask.", epilog=_EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = p.add_subparsers(dest="command", required=True)
    r = sub.add_parser("run", help="run (or resume) a study into a Parquet dataset")
    r.add_argument("study", help="a TOML file, or a built-in study (pcr-study list)")
    r.add_argument("--output", required=True, help="directory of the results (Parquet dataset)")
    r.add_argument("--trials", type=_positive, help="trials per combination of levels "
                   "(default: the study's)")
    r.add_argument("--workers", type=_positive, help="worker processes of the local cluster "
                   "(default: one per core)")
    r.add_argument("--scheduler", help="address of a running Dask scheduler, e.g. "
                   "tcp://host:8786 (instead of a local cluster)")
    r.add_argument("--batch-size", type=_positive, help="trials per task (default: up to 8)")
    r.add_argument("--flush-seconds", type=float, default=10.0, help="write the finished "
                   "trials every this many seconds (default: %(default)s): what a killed run can lose; "
                   "Ctrl-C writes them all")
    r.add_argument("--quiet", action="store_true", help="no progress line")
    q = sub.add_parser("plot", help="accuracy against each varied factor, and their ranking")
    q.add_argument("results", help="directory written by pcr-study run")
    q.add_argument("--output", help="directory of the PNG and CSV files (default: "
                   "RESULTS/_plots, which Parquet readers skip)")
    q.add_argument("--outcome", action="append", help="an outcome column to plot (repeatable; "
                   "default: validation e_p of the identified and the nominal model, e_theta, AP_p on the "
                   "square)")
    m = sub.add_parser("summary", help="failures, Table 3 over the trials, branch mismatches, "
                       "unmeasured configurations and times, in Markdown")
    m.add_argument("results", help="directory written by pcr-study run")
    sub.add_parser("list", help="the built-in studies")
    return p


def _run(args):
    from .study import run

    if args.workers is not None and args.scheduler is not None:
        raise ValueError("--workers is for the local cluster; give it or --scheduler, not both")
    table = run(args.study, args.output, trials=args.trials, workers=args.workers,
                scheduler=args.scheduler, batch_size=args.batch_size, progress=not args.quiet,
                flush_seconds=args.flush_seconds)
    failed = int(table["failure"].notna().sum())
    print(f"{len(table)} trials in {args.output} ({failed} failed)")


def _plot(args):
    from .study import plot

    for path in plot(args.results, args.output, args.outcome):
        print(path)


def _summary(args):
    from .study import summary

    print(summary(args.results), end="")


def _list(_):
    from .study import Study, builtin_studies

    for name in builtin_studies():
        study = Study.load(name)
        levels = "; ".join(f"{k} = {v}" for k, v in study.levels.items())
        print(f"{name}: {study.description} ({study.trials} trials x {levels})")


def main(argv=None):
    args = _parser().parse_args(argv)
    try:
        {"run": _run, "plot": _plot, "summary": _summary, "list": _list}[args.command](args)
    except KeyboardInterrupt:
        print("pcr-study: stopped; the finished trials are written, and running the same "
              "command again resumes the study", file=sys.stderr)
        return 130
    except (OSError, ValueError, ModuleNotFoundError) as e:
        print(f"pcr-study: error: {e}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
