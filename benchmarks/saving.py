"""What a benchmark step leaves behind: its raw data, its report and the project's targets checked."""

import json
import sys
from pathlib import Path

import numpy as np


def measure_and_save(args, name, run, report, checks):
    """Run a benchmark step and keep what it found, for the steps of ``make bench``.

    ``run(quick=, seed=, log=)`` measures (seeded, floating-point warnings off) and returns the raw
    data, written to ``OUT/NAME.json`` first; ``report(raw)`` is printed; ``checks(raw)`` gives
    ``(missed, lines)``, the project's targets against the figures, written to
    ``OUT/checks-NAME.txt`` and counted on stderr.  Returns the raw data.
    """
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    with np.errstate(all="ignore"):
        raw = run(quick=args.quick, seed=args.seed, log=lambda text: print(text, file=sys.stderr, flush=True))
    (out / f"{name}.json").write_text(json.dumps(raw, indent=1))
    print(report(raw))
    print(f"raw data: {out / f'{name}.json'}")
    missed, lines = checks(raw)
    verdicts = out / f"checks-{name}.txt"
    verdicts.write_text("\n".join(lines) + "\n", encoding="utf-8")
    print(f"the project's targets: {len(lines) - missed} of {len(lines)} met ({verdicts})", file=sys.stderr)
    return raw
