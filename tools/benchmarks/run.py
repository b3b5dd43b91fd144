#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Run the benchmarks of tools/benchmarks/benchmarks.toml and store what each printed.

Each entry's command runs from the repository root; its output (parsed as the manifest's
`output` says) is stored under docs/benchmarks/results/ID.json with the command, the commit,
the UTC date, the machine (CPU model, CPUs, load average at start) and the wall time, so a
figure on the page always says where it came from. render.py then writes the page.

  tools/benchmarks/run.py                      every quick and slow entry
  tools/benchmarks/run.py --quick              the quick ones only
  tools/benchmarks/run.py --only ID [ID ...]   these (needs-root-or-vm ones only this way)
  tools/benchmarks/run.py --only hil --from-log GUEST.log   parse a log the command wrote
"""
import argparse
import datetime
import json
import os
import re
import subprocess
import sys
import time

import benchmarks


def git(*args):
    return subprocess.run(["git", *args], cwd=benchmarks.REPO, capture_output=True, text=True,
                          check=True).stdout.strip()


def cpu_model():
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return "unknown"


def number_or_text(value):
    """A printed figure as a number when it is one, so the page can format it."""
    try:
        return int(value) if value.lstrip("-").isdigit() else float(value)
    except ValueError:
        return value


def parse_output(entry, text):
    """The command's stdout as data: one JSON document, JSON lines, figures matched in text, or
    HIL figure lines."""
    kind = entry["output"]
    if kind == "json":
        return json.loads(text)
    if kind == "json-lines":
        return [json.loads(line) for line in text.splitlines() if line.strip().startswith("{")]
    if kind == "text":
        # The manifest's patterns: name -> a regular expression whose one group is the figure.
        figures = {}
        for name, pattern in entry.get("patterns", {}).items():
            match = re.search(pattern, text, re.M)
            if not match:
                raise ValueError(f"pattern {name} ({pattern}) not found")
            figures[name] = number_or_text(match.group(1))
        return figures
    if kind == "hil-log":
        # WEEDSPRAY-HIL key=value figures; the last value of a key counts, as the VM test reads it.
        figures, steps, verdict = {}, {}, None
        for line in text.splitlines():
            if line.startswith("WEEDSPRAY-HIL "):
                key, _, value = line[len("WEEDSPRAY-HIL "):].partition("=")
                if value:
                    figures[key.strip()] = number_or_text(value.strip())
            elif line.startswith("WEEDSPRAY-HIL-STEP "):
                name, _, rest = line[len("WEEDSPRAY-HIL-STEP "):].partition(" ")
                steps[name] = rest.split(":", 1)[0]
            elif line.startswith("WEEDSPRAY-HIL-RESULT "):
                verdict = line[len("WEEDSPRAY-HIL-RESULT "):]
        if not figures:
            raise ValueError("no WEEDSPRAY-HIL figure lines")
        return {"figures": figures, "steps": steps, "verdict": verdict}
    raise SystemExit(f"{entry['id']}: unknown output kind '{kind}'")


def run_entry(entry, results_dir, from_log=None):
    dirty = bool(git("status", "--porcelain", "--untracked-files=no", "--", ".",
                     ":(exclude)docs", ":(exclude)tools/benchmarks"))
    record = {
        "id": entry["id"],
        "command": entry["command"],
        "env": entry["env"],
        "commit": git("rev-parse", "HEAD"),
        "local_changes": dirty,
        "date_utc": datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M"),
        "machine": {
            "cpu": cpu_model(),
            "nproc": os.cpu_count(),
            "load_average_start": [round(x, 2) for x in os.getloadavg()],
        },
    }
    if from_log:
        # The command ran elsewhere (a VM, a board): only its log is parsed here.
        with open(from_log, errors="replace") as f:
            text = f.read()
        record["from_log"] = os.path.basename(from_log)
        record["wall_s"] = None
        record["exit_status"] = None
    else:
        env = dict(os.environ, **entry["env"])
        print(f"[{entry['id']}] {entry['command']}", file=sys.stderr, flush=True)
        start = time.monotonic()
        done = subprocess.run(["bash", "-c", entry["command"]], cwd=benchmarks.REPO, env=env,
                              stdout=subprocess.PIPE, text=True)
        record["wall_s"] = round(time.monotonic() - start, 1)
        record["exit_status"] = done.returncode
        text = done.stdout
        if done.returncode not in entry["ok_exit"]:
            print(f"[{entry['id']}] exit status {done.returncode}; result not stored",
                  file=sys.stderr)
            return False
    try:
        record["result"] = parse_output(entry, text)
    except ValueError as error:
        print(f"[{entry['id']}] output not {entry['output']}: {error}; result not stored\n{text[-2000:]}",
              file=sys.stderr)
        return False
    path = benchmarks.write_result(results_dir, entry["id"], record)
    print(f"[{entry['id']}] {record['wall_s']} s -> {path}", file=sys.stderr)
    return True


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--only", nargs="+", metavar="ID", help="run these entries")
    parser.add_argument("--quick", action="store_true", help="run the quick entries only")
    parser.add_argument("--from-log", metavar="FILE",
                        help="parse this log instead of running the command (one --only entry)")
    parser.add_argument("--results-dir", default=benchmarks.RESULTS,
                        help="where results are stored (default docs/benchmarks/results)")
    parser.add_argument("--manifest", default=benchmarks.MANIFEST)
    parser.add_argument("--list", action="store_true", help="list the entries and exit")
    args = parser.parse_args()
    manifest = benchmarks.load_manifest(args.manifest)
    if args.list:
        for entry in manifest.values():
            print(f"{entry['id']:20} {entry['cost']:17} {entry['command']}")
        return 0
    if args.only:
        unknown = [i for i in args.only if i not in manifest]
        if unknown:
            parser.error(f"unknown id(s): {' '.join(unknown)} (--list shows them)")
        chosen = [manifest[i] for i in args.only]
    else:
        costs = ("quick",) if args.quick else ("quick", "slow")
        chosen = [e for e in manifest.values() if e["cost"] in costs]
    if args.from_log and len(chosen) != 1:
        parser.error("--from-log takes exactly one --only ID")
    failed = [e["id"] for e in chosen if not run_entry(e, args.results_dir, args.from_log)]
    if failed:
        print(f"failed: {' '.join(failed)}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
