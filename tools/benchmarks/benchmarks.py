# SPDX-License-Identifier: Apache-2.0
"""The benchmarks page's shared parts: the manifest, the stored results and their paths."""
import json
import pathlib
import tomllib

REPO = pathlib.Path(__file__).resolve().parents[2]
MANIFEST = REPO / "tools" / "benchmarks" / "benchmarks.toml"
RESULTS = REPO / "docs" / "benchmarks" / "results"
TEMPLATE = REPO / "docs" / "benchmarks" / "page.md.in"
PAGE = REPO / "docs" / "benchmarks.md"

# What an entry costs to run: run.py runs the first two by default, the last only by name.
COSTS = ("quick", "slow", "needs-root-or-vm")


def load_manifest(path=MANIFEST):
    """The manifest's entries by id, in file order; fails on a missing key or bad cost."""
    with open(path, "rb") as f:
        entries = tomllib.load(f)["benchmark"]
    by_id = {}
    for entry in entries:
        for key in ("id", "section", "command", "cost"):
            if key not in entry:
                raise SystemExit(f"{path}: an entry lacks '{key}': {entry}")
        if entry["cost"] not in COSTS:
            raise SystemExit(f"{path}: {entry['id']}: cost must be one of {COSTS}")
        if entry["id"] in by_id:
            raise SystemExit(f"{path}: id {entry['id']} twice")
        entry.setdefault("output", "json")
        entry.setdefault("env", {})
        entry.setdefault("ok_exit", [0])
        entry.setdefault("tables", {})
        by_id[entry["id"]] = entry
    return by_id


def result_path(results_dir, entry_id):
    return pathlib.Path(results_dir) / f"{entry_id}.json"


def read_result(results_dir, entry_id):
    path = result_path(results_dir, entry_id)
    if not path.exists():
        raise SystemExit(f"no stored result for '{entry_id}' ({path}): tools/benchmarks/run.py --only {entry_id}")
    with open(path) as f:
        return json.load(f)


def write_result(results_dir, entry_id, record):
    path = result_path(results_dir, entry_id)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(record, indent=2, sort_keys=True) + "\n")
    return path
