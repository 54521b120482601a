"""Splices the tables the benchmark just measured into README.md (and other Markdown files, e.g.
doc/benchmark.md), between their '<!-- BEGIN GENERATED name ... -->' and
'<!-- END GENERATED name -->' markers, so that they show what scripts/bench.sh produced and
nothing typed by hand. README.md must hold every block; the other files, the blocks they have.
Usage: update_readme.py RESULTS_DIR README.md [OTHER.md ...]"""
import pathlib
import re
import sys


def ratio_table(summary: str) -> str:
    """summary.md from its explanation of the ratio table down to the first plot."""
    lines = summary.splitlines()
    start = next(i for i, line in enumerate(lines) if line.startswith("CPU time per"))
    end = next((i for i in range(start, len(lines)) if lines[i].startswith("![")), len(lines))
    return "\n".join(lines[start:end]).strip()


def has_block(text: str, name: str) -> bool:
    return re.search(r"<!-- BEGIN GENERATED %s[^>]*-->\n" % name, text) is not None


def splice(text: str, name: str, body: str, path: pathlib.Path) -> str:
    pattern = re.compile(r"(<!-- BEGIN GENERATED %s[^>]*-->\n).*?(<!-- END GENERATED %s -->)" % (name, name),
                         re.S)
    if not pattern.search(text):
        sys.exit(f"update_readme.py: {path} has no GENERATED {name} markers")
    return pattern.sub(lambda m: m.group(1) + body + "\n" + m.group(2), text)


results = pathlib.Path(sys.argv[1])
targets = [pathlib.Path(arg) for arg in sys.argv[2:]]
blocks = {"work_precision": ratio_table((results / "summary.md").read_text())}
for name in ("default_ratio", "default_ratio_summary", "reinit_cost", "extreme_cases", "fuzz", "soak", "sweep", "node_load"):
    path = results / f"{name}.md"
    if path.exists():
        blocks[name] = path.read_text().strip()
    else:
        print(f"update_readme.py: no {path}; its GENERATED {name} block is left as it is")
for i, path in enumerate(targets):
    text = path.read_text()
    for name, body in blocks.items():
        if i == 0 or has_block(text, name):  # the README must have every block
            text = splice(text, name, body, path)
    path.write_text(text)
    print(f"update_readme.py: tables of {results} spliced into {path}")
