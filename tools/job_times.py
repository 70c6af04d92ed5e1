#!/usr/bin/env python
"""Record the measured wall time and peak memory of every workflow job.

    python tools/job_times.py [RESULTS_DIR] [--out config/job_times.yaml]

Reads ``provenance.run`` of every ``RESULTS_DIR/<artefact>.json`` (``job``,
``module_wall_time_s``, ``peak_rss_mb``, ``quick``; written by ``hpfebe run``) and writes
one figure per job: the Snakefile orders a fresh machine's first run longest job first
from it (on later runs each job's own last result gives its time).  Run it after a full
``snakemake -j2`` on a quiet machine and commit the file.
"""

from __future__ import annotations

import argparse
import json
import platform
import sys
from datetime import datetime, timezone
from pathlib import Path

import yaml

ROOT = Path(__file__).resolve().parents[1]


def cpu_model() -> str:
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine()


def job_figures(results: Path) -> dict[str, dict]:
    """job -> {"wall_s", "peak_mb", "quick"} from the results' provenance."""
    out: dict[str, dict] = {}
    for f in sorted(results.glob("*.json")):
        try:
            run = json.loads(f.read_text())["provenance"]["run"]
        except (OSError, ValueError, KeyError, TypeError):
            continue
        job = run.get("job") or run.get("module")
        if job and "module_wall_time_s" in run:
            out[job] = {"wall_s": float(run["module_wall_time_s"]),
                        "peak_mb": run.get("peak_rss_mb"), "quick": bool(run.get("quick"))}
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("results", nargs="?", default=str(ROOT / "results"))
    ap.add_argument("--out", default=str(ROOT / "config" / "job_times.yaml"))
    args = ap.parse_args(argv)
    figures = job_figures(Path(args.results))
    if not figures:
        print(f"no results with provenance in {args.results}", file=sys.stderr)
        return 1
    if any(v["quick"] for v in figures.values()):
        print("refusing: some results are quick runs (record a full run)", file=sys.stderr)
        return 1
    doc = {
        "measured": {"date": datetime.now(timezone.utc).strftime("%Y-%m-%d"),
                     "cpu": cpu_model(),
                     "threads_per_job": 1, "configuration": "config/config.yaml"},
        "wall_s": {j: round(v["wall_s"], 1) for j, v in sorted(figures.items())},
        "peak_mb": {j: v["peak_mb"] for j, v in sorted(figures.items())
                    if v["peak_mb"] is not None},
    }
    text = ("# Measured per-job figures of a full run (tools/job_times.py writes this file).\n"
            + yaml.safe_dump(doc, sort_keys=False))
    Path(args.out).write_text(text)
    print(f"wrote {args.out}: {len(figures)} jobs")
    return 0


if __name__ == "__main__":
    sys.exit(main())
