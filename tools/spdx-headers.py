#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Every code file of the project names its licence in an SPDX line near its top.

  tools/spdx-headers.py [--source DIR]          list the files without one; exit 1 if any
  tools/spdx-headers.py [--source DIR] --fix    add the line where it is missing

Code is what git tracks (every file under DIR when it is not a git checkout) of these kinds:
C++ and JavaScript (//), shell, Python and CMake (#, after a shebang), HTML (<!-- -->, after a
doctype). Data, models, configuration and documents keep their own licences (NOTICE,
systemd/debian/copyright) and are not checked.
"""
import argparse
import pathlib
import subprocess
import sys

LINE = "SPDX-License-Identifier: Apache-2.0"
SCRIPTS_WITHOUT_SUFFIX = {"dev", ".ci/run", ".githooks/commit-msg", "systemd/debian/postinst"}
LOOK_WITHIN_LINES = 3


def comment_style(relative: str):
    path = pathlib.PurePosixPath(relative)
    if path.suffix in (".cpp", ".hpp", ".js"):
        return "//"
    if path.suffix in (".sh", ".py", ".cmake") or path.name == "CMakeLists.txt":
        return "#"
    if relative in SCRIPTS_WITHOUT_SUFFIX or relative.startswith("tools/completion/"):
        return "#"
    if path.suffix == ".html":
        return "<!--"
    return None


def tracked_files(source: pathlib.Path):
    if (source / ".git").exists():
        listed = subprocess.run(["git", "-C", str(source), "ls-files"], capture_output=True,
                                text=True, check=True).stdout
        return [name for name in listed.splitlines() if name]
    skip = {".git", "build"}
    return [str(p.relative_to(source)) for p in source.rglob("*")
            if p.is_file() and not skip.intersection(p.relative_to(source).parts)]


def has_line(text: str) -> bool:
    return any(LINE in line for line in text.split("\n")[:LOOK_WITHIN_LINES])


def with_line(text: str, style: str) -> str:
    lines = text.split("\n")
    if style == "<!--":
        header, at = f"<!-- {LINE} -->", 1 if lines[0].lower().startswith("<!doctype") else 0
    else:
        header, at = f"{style} {LINE}", 1 if lines[0].startswith("#!") else 0
    lines.insert(at, header)
    return "\n".join(lines)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--source", default=pathlib.Path(__file__).resolve().parent.parent,
                        type=pathlib.Path, help="the project's root (default: this checkout)")
    parser.add_argument("--fix", action="store_true", help="add the line where it is missing")
    args = parser.parse_args()
    missing = []
    for relative in tracked_files(args.source):
        style = comment_style(relative)
        path = args.source / relative
        if style is None or not path.is_file():
            continue
        text = path.read_text(encoding="utf-8")
        if has_line(text):
            continue
        if args.fix:
            path.write_text(with_line(text, style), encoding="utf-8")
        missing.append(relative)
    for relative in missing:
        print(f"{relative}: {'added' if args.fix else 'no'} '{LINE}' line")
    if missing and not args.fix:
        print(f"{len(missing)} code files without an SPDX line; add them with {sys.argv[0]} --fix")
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
