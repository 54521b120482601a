"""Splices the tables the benchmark just measured into README.md, between its
'<!-- BEGIN GENERATED name ... -->' and '<!-- END GENERATED name -->' markers, so that the README
shows what scripts/bench.sh produced and nothing typed by hand.
Usage: update_readme.py RESULTS_DIR README.md"""
import pathlib
import re
import sys


def ratio_table(summary: str) -> str:
    """summary.md from its explanation of the ratio table down to the first plot."""
    lines = summary.splitlines()
    start = next(i for i, line in enumerate(lines) if line.startswith("CPU time per"))
    end = next((i for i in range(start, len(lines)) if lines[i].startswith("![")), len(lines))
    return "\n".join(lines[start:end]).strip()


def splice(readme: str, name: str, body: str) -> str:
    pattern = re.compile(r"(<!-- BEGIN GENERATED %s[^>]*-->\n).*?(<!-- END GENERATED %s -->)" % (name, name),
                         re.S)
    if not pattern.search(readme):
        sys.exit(f"update_readme.py: README has no GENERATED {name} markers")
    return pattern.sub(lambda m: m.group(1) + body + "\n" + m.group(2), readme)


results = pathlib.Path(sys.argv[1])
readme_path = pathlib.Path(sys.argv[2])
readme = readme_path.read_text()
readme = splice(readme, "work_precision", ratio_table((results / "summary.md").read_text()))
extreme = results / "extreme_cases.md"
if extreme.exists():
    readme = splice(readme, "extreme_cases", extreme.read_text().strip())
readme_path.write_text(readme)
print(f"update_readme.py: tables of {results} spliced into {readme_path}")
