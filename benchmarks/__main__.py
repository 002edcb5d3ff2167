"""Run the benchmark suite: ``python -m benchmarks`` (what ``make bench`` runs).

Steps, each from the saved output of the one before:

1. the suite (:mod:`benchmarks.suite`), with a progress bar on stderr,
   writes ``OUT/raw.json``;
2. the stability sweeps of the primitive pairs
   (:mod:`benchmarks.pair_stability`) write ``OUT/pair_stability.json``;
3. the charts (:mod:`benchmarks.charts`) and ``OUT/report.md``
   (:mod:`benchmarks.report`) are drawn from those files;
4. the speed comparison (``python -m benchmarks.speed``, when present)
   runs in a new process; its output is saved to ``OUT/speed.txt`` and
   added to the report, and its verdicts on the project's targets to
   ``OUT/checks-speed.txt``, apart from what the report shows (one line on
   stderr counts them).

Options: ``--quick`` for a smoke run (small batches; about half a minute
for the suite on two cores, kernels cached), ``--seed``,
``--out DIR`` (default ``bench-results``), ``--report-only`` to redraw the
charts and report from existing raw data, ``--no-pairs`` and ``--no-speed``
to skip step 2 or 4, and ``--publish`` to copy the charts to ``docs/`` and
rewrite the benchmark sections of ``docs/benchmarks.md`` from the same data; ``--package-python`` is passed
to the speed step (``make bench`` gives it an environment with the package
alone, for the start-up rows).
"""

import argparse
import dataclasses
import importlib.util
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def run_speed(quick, path, package_python=None, checks=None):
    """Run ``python -m benchmarks.speed`` in a new process, echoing and saving
    its output (with any traceback) to ``path``.

    A new process, because the step times kernels against other libraries:
    after the suite, this process's heap (and with it what fresh pages cost,
    see ``benchmarks/speed.py``) is in a state no other run of the step
    shares, and the step's table should be the one its own command gives.

    Returns
    -------
    bool
        False if the step failed; True if it ran or is not there yet.
    """
    if importlib.util.find_spec("benchmarks.speed") is None:
        print("benchmarks.speed is not there yet: speed step skipped", file=sys.stderr)
        path.unlink(missing_ok=True)
        return True
    command = [sys.executable, "-m", "benchmarks.speed"] + (["--quick"] if quick else [])
    if package_python:
        command += ["--package-python", package_python]
    if checks is not None:
        command += ["--checks", str(checks)]
    lines = []
    with subprocess.Popen(
        command, cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True
    ) as child:
        for line in child.stdout:
            sys.stdout.write(line)
            sys.stdout.flush()
            lines.append(line)
    path.write_text("".join(lines), encoding="utf-8")
    return child.returncode == 0


def main(argv=None):
    parser = argparse.ArgumentParser(
        prog="python -m benchmarks", description="Accuracy, speed and stability of every method and backend."
    )
    parser.add_argument("--quick", action="store_true", help="a smoke run: small batches, three K")
    parser.add_argument("--seed", type=int, default=0, help="seed of every scene (default 0)")
    parser.add_argument("--out", type=Path, default=Path("bench-results"), help="output directory")
    parser.add_argument(
        "--report-only", action="store_true", help="redraw charts and report from OUT/raw.json"
    )
    parser.add_argument("--no-pairs", action="store_true", help="skip the primitive pairs' stability sweeps")
    parser.add_argument("--no-speed", action="store_true", help="skip the speed comparison step")
    parser.add_argument(
        "--publish",
        action="store_true",
        help="copy the charts to docs/ and rewrite the benchmark section of docs/benchmarks.md",
    )
    parser.add_argument("--no-progress", action="store_true", help="no progress bar")
    parser.add_argument(
        "--package-python",
        metavar="PYTHON",
        help="passed to the speed step: an interpreter with the package and its dependencies alone",
    )
    args = parser.parse_args(argv)

    # Imported here so that --help answers without loading numba and the libraries.
    from benchmarks import charts, pair_stability, report, suite

    out = args.out
    raw_path = out / "raw.json"
    speed_path = out / "speed.txt"
    pairs_path = out / "pair_stability.json"
    ok = True
    if not args.report_only:
        speed_path.unlink(missing_ok=True)  # a previous run's, which this run's report must not show
        pairs_path.unlink(missing_ok=True)
        config = suite.QUICK if args.quick else suite.DEFAULT
        config = dataclasses.replace(config, seed=args.seed)
        start = time.perf_counter()
        raw = suite.run(config, progress=not args.no_progress)
        suite.save(raw, raw_path)
        print(f"raw results: {raw_path} ({time.perf_counter() - start:.0f} s)", file=sys.stderr)
        if not args.no_pairs:
            pairs_config = pair_stability.QUICK if args.quick else pair_stability.DEFAULT
            pairs_config = dataclasses.replace(pairs_config, seed=args.seed)
            pairs_raw = pair_stability.run(pairs_config, log=lambda text: print(text, file=sys.stderr))
            suite.save(pairs_raw, pairs_path)
    raw = suite.load(raw_path)
    pngs = charts.draw_all(raw, out)
    pairs_raw = suite.load(pairs_path) if pairs_path.exists() else None
    pairs_chart = charts.stability_pairs(pairs_raw, out / "stability_pairs.png") if pairs_raw else None
    pairs_text = pair_stability.markdown(pairs_raw, pairs_chart, by_point=True) if pairs_raw else None
    report.write(raw, out, pngs, speed_path if speed_path.exists() else None, pairs_text)
    if not args.report_only and not args.no_speed:
        checks = out / "checks-speed.txt"
        checks.unlink(missing_ok=True)
        ok = run_speed(raw["meta"]["config"]["quick"], speed_path, args.package_python, checks)
        report.write(raw, out, pngs, speed_path if speed_path.exists() else None, pairs_text)
        if checks.exists():
            verdicts = checks.read_text(encoding="utf-8").splitlines()
            missed = sum(line.startswith("MISSED") for line in verdicts)
            print(f"the project's targets: {len(verdicts) - missed} of {len(verdicts)} met ({checks})",
                  file=sys.stderr)  # fmt: skip
    print(f"report: {out / 'report.md'}", file=sys.stderr)
    if args.publish:
        report.publish(raw, pngs, docs=ROOT / "docs", page=ROOT / "docs" / "benchmarks.md")
        if pairs_raw:
            pair_stability.publish(pairs_raw, pairs_chart)
        print("published: docs/*.png and the benchmark sections of docs/benchmarks.md", file=sys.stderr)
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
