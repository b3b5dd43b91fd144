# SPDX-License-Identifier: Apache-2.0
"""docs/benchmarks.md is what tools/benchmarks/render.py writes, and the tools still work."""
import json
import os
import pathlib
import shutil
import subprocess
import sys
import tempfile
import unittest

import benchmarks
import render
import run

TOOLS = benchmarks.REPO / "tools" / "benchmarks"
# A quick entry that needs no data set (bench-vision falls back to a synthetic field).
QUICK_ENTRY = "vision-speed"


def tool(name, *args):
    return subprocess.run([sys.executable, str(TOOLS / name), *args], cwd=benchmarks.REPO,
                          capture_output=True, text=True)


class CommittedPage(unittest.TestCase):
    def test_page_is_rendered_from_the_committed_results(self):
        done = tool("render.py", "--check")
        self.assertEqual(done.returncode, 0,
                         "docs/benchmarks.md is stale or hand-edited:\n" + done.stdout[-4000:]
                         + done.stderr)

    def test_every_template_placeholder_names_a_manifest_entry(self):
        manifest = benchmarks.load_manifest()
        template = benchmarks.TEMPLATE.read_text()
        for match in render.PLACEHOLDER.finditer(template):
            words = match.group(1).split()
            entry_id = words[1] if words[0] in ("run", "table") else match.group(1).split(":")[0]
            self.assertIn(entry_id, manifest, match.group(0))


class QuickEntryRunsAndRenders(unittest.TestCase):
    def test_quick_entry_runs_and_its_result_renders(self):
        manifest = benchmarks.load_manifest()
        self.assertEqual(manifest[QUICK_ENTRY]["cost"], "quick")
        with tempfile.TemporaryDirectory() as tmp:
            results = pathlib.Path(tmp) / "results"
            shutil.copytree(benchmarks.RESULTS, results)
            os.remove(results / f"{QUICK_ENTRY}.json")
            done = tool("run.py", "--only", QUICK_ENTRY, "--results-dir", str(results))
            self.assertEqual(done.returncode, 0, done.stderr)
            record = json.loads((results / f"{QUICK_ENTRY}.json").read_text())
            for key in ("command", "commit", "date_utc", "machine", "wall_s", "result"):
                self.assertIn(key, record)
            self.assertGreater(record["result"]["pipeline_ms_median"], 0)
            page = pathlib.Path(tmp) / "benchmarks.md"
            done = tool("render.py", "--results-dir", str(results), "--out", str(page))
            self.assertEqual(done.returncode, 0, done.stderr)
            words = " ".join(page.read_text().split())  # the prose wraps anywhere
            self.assertNotIn("{{", words)
            for expected in (f"`{QUICK_ENTRY}`, {record['date_utc']} UTC",
                             f"median {record['result']['pipeline_ms_median']:.2f} ms"):
                self.assertTrue(expected in words, f"'{expected}' not on the rendered page")


class Renderer(unittest.TestCase):
    def render(self, template, result):
        manifest = {"x": {"id": "x", "command": "true", "env": {}, "tables": {
            "t": {"rows": "rows", "sort": "-v", "where": {"k": ["a", "b"]},
                  "columns": [["k", "k"], ["v", "v", ".1f"]]},
            "g": {"rows": "rows", "group_by": "k",
                  "columns": [["k", "k"], ["n", "v", "", "count"], ["mean", "v", ".1f", "mean"],
                              ["max", "v", "", "max"]]}}}}
        with tempfile.TemporaryDirectory() as tmp:
            benchmarks.write_result(tmp, "x", {
                "commit": "0" * 40, "date_utc": "2000-01-01 00:00", "wall_s": 1.0,
                "machine": {"cpu": "cpu", "nproc": 2, "load_average_start": [0.5, 0, 0]},
                "result": result})
            return render.render(template, manifest, tmp)

    def test_values_selectors_and_tables(self):
        rows = [{"k": "a", "v": 1}, {"k": "b", "v": 2}, {"k": "c", "v": 3}]
        page = self.render("{{x:rows[k=b].v|.2f}} {{x:rows.0.k}}\n{{table x t}}\n",
                           {"rows": rows})
        self.assertIn("2.00 a\n", page)
        self.assertIn("| k | v |\n|---|---|\n| b | 2.0 |\n| a | 1.0 |\n", page)

    def test_grouped_table_aggregates_each_group(self):
        rows = [{"k": "a", "v": 1}, {"k": "b", "v": 4}, {"k": "a", "v": 3}]
        page = self.render("{{table x g}}\n", {"rows": rows})
        self.assertIn("| a | 2 | 2.0 | 3 |\n| b | 1 | 4.0 | 4 |\n", page)

    def test_a_missing_value_fails_the_render(self):
        with self.assertRaisesRegex(render.RenderError, "no 'nope'"):
            self.render("{{x:nope}}", {"rows": []})
        with self.assertRaisesRegex(render.RenderError, "no element"):
            self.render("{{x:rows[k=z].v}}", {"rows": [{"k": "a"}]})
        with self.assertRaisesRegex(render.RenderError, "no entry 'y'"):
            self.render("{{run y}}", {})


class OutputParsing(unittest.TestCase):
    def test_text_output_takes_each_patterns_group(self):
        entry = {"id": "x", "output": "text",
                 "patterns": {"edges": r"placement: (\d+) edges", "p95": r"p95 ([0-9.]+) cm"}}
        figures = run.parse_output(entry, "noise\nplacement: 62 edges, p95 1.42 cm\n")
        self.assertEqual(figures, {"edges": 62, "p95": 1.42})
        with self.assertRaisesRegex(ValueError, "edges"):
            run.parse_output(entry, "no figures here\n")

    def test_hil_log_keeps_figures_steps_and_verdict(self):
        log = ("boot noise\nWEEDSPRAY-HIL kill9_unsafe_ms=4.2\n"
               "WEEDSPRAY-HIL-STEP kill9_safe PASS: written 0\n"
               "WEEDSPRAY-HIL kill9_unsafe_ms=5.0\nWEEDSPRAY-HIL-RESULT PASS steps=1 failed=0\n")
        parsed = run.parse_output({"id": "hil", "output": "hil-log"}, log)
        self.assertEqual(parsed["figures"], {"kill9_unsafe_ms": 5.0})
        self.assertEqual(parsed["steps"], {"kill9_safe": "PASS"})
        self.assertEqual(parsed["verdict"], "PASS steps=1 failed=0")

    def test_json_lines_ignore_other_lines(self):
        parsed = run.parse_output({"id": "m", "output": "json-lines"},
                                  'starting\n{"a": 1}\n{"a": 2}\n')
        self.assertEqual(parsed, [{"a": 1}, {"a": 2}])


if __name__ == "__main__":
    unittest.main()
