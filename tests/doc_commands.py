#!/usr/bin/env python3
"""Runs a document's commands as written (CTest: Docs.*).

Usage: doc_commands.py SOURCE_DIR BUILD_DIR DOC.md

- every ```sh block runs in bash -e, in a fresh directory where `build` is BUILD_DIR and the
  source tree's top-level entries are linked, so `build/bin/dpc31 ...` and `traces/...` work as
  in a clone; it must exit 0;
- a fenced block right after the comment `<!-- output -->` must equal the stdout of the sh
  block before it;
- a fenced block right after `<!-- file: PATH -->` must equal the source file PATH.
Prints one line per check; exit 1 on the first difference.
"""

import difflib
import os
import re
import subprocess
import sys
import tempfile

FENCE = re.compile(r"^```(\w*)\n(.*?)^```\n", re.S | re.M)
MARK = re.compile(r"<!-- (output|file: (\S+)) -->\s*$")


def fail(doc, line, what, want=None, got=None):
    print(f"{doc}:{line}: {what}", file=sys.stderr)
    if want is not None:
        sys.stderr.writelines(difflib.unified_diff(want.splitlines(True), got.splitlines(True),
                                                   "document", "actual"))
    sys.exit(1)


def main():
    src, build, doc = sys.argv[1:4]
    text = open(doc, encoding="utf-8").read()
    last_stdout = None
    checks = 0
    with tempfile.TemporaryDirectory() as work:
        for entry in os.listdir(src):
            if entry not in ("build", ".git"):
                os.symlink(os.path.join(src, entry), os.path.join(work, entry))
        os.symlink(build, os.path.join(work, "build"))
        for m in FENCE.finditer(text):
            lang, body = m.group(1), m.group(2)
            line = text.count("\n", 0, m.start()) + 1
            before = text[:m.start()].rstrip("\n").rsplit("\n", 1)[-1]
            mark = MARK.search(before)
            if mark and mark.group(1) == "output":
                if last_stdout is None:
                    fail(doc, line, "an output block with no sh block before it")
                if last_stdout != body:
                    fail(doc, line, "the output differs", body, last_stdout)
                print(f"{doc}:{line}: output as documented")
                checks += 1
            elif mark:
                path = mark.group(2)
                actual = open(os.path.join(src, path), encoding="utf-8").read()
                if actual != body:
                    fail(doc, line, f"differs from {path}", body, actual)
                print(f"{doc}:{line}: equals {path}")
                checks += 1
            elif lang == "sh":
                r = subprocess.run(["bash", "-e", "-c", body], cwd=work, capture_output=True,
                                   text=True, timeout=300)
                if r.returncode != 0:
                    fail(doc, line, f"exit {r.returncode}: {r.stderr.strip()}")
                last_stdout = r.stdout
                print(f"{doc}:{line}: sh block ran")
                checks += 1
    if checks == 0:
        fail(doc, 1, "nothing to check")


if __name__ == "__main__":
    main()
