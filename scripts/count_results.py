"""Counts the test cases in the JUnit XML files of a catkin test_results folder and prints
the plain 'N passed, N failed' line; exits 1 on any failure, error, or no test at all."""
import sys
import pathlib
import xml.etree.ElementTree as ET

root = pathlib.Path(sys.argv[1])
passed = failed = skipped = 0
for path in sorted(root.rglob("*.xml")):
    try:
        tree = ET.parse(path)
    except ET.ParseError as error:
        print(f"unreadable result file {path}: {error}")
        failed += 1
        continue
    cases = tree.getroot().iter("testcase")
    for case in cases:
        if case.find("failure") is not None or case.find("error") is not None:
            failed += 1
            print(f"FAILED: {path.parent.name}/{path.name}: {case.get('classname')}.{case.get('name')}")
        elif case.find("skipped") is not None:
            skipped += 1
        else:
            passed += 1
print(f"{passed} passed, {failed} failed, {skipped} skipped")
sys.exit(1 if failed or passed == 0 else 0)
