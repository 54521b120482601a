"""The core's outputs are bit-identical to the reference build's (test/golden/golden.py, issue 17):
every scene x integrator, the shipped and extreme scene files at two output rates, events, step
budgets and the Python module's rows. A change that alters one bit of any output fails here; a
change meant to alter results regenerates test/golden/outputs.txt and says why in its commit."""
import importlib.util

from conftest import SOURCE_DIR

spec = importlib.util.spec_from_file_location("golden", SOURCE_DIR / "test" / "golden" / "golden.py")
golden = importlib.util.module_from_spec(spec)
spec.loader.exec_module(golden)


def test_outputs_are_bit_identical_to_the_reference_build(simulate):
    expected = golden.read_manifest(golden.MANIFEST)
    actual = {name: (code, digest) for name, code, digest in golden.outputs(simulate)}
    assert sorted(actual) == sorted(expected), "the case matrix differs from the manifest's"
    differing = [name for name in expected if actual[name] != expected[name]]
    assert not differing, f"{len(differing)} of {len(expected)} outputs differ: {differing[:20]}"
    # The matrix covers what it claims: refusals, step budgets and events are in it.
    codes = [code for code, _ in expected.values()]
    assert codes.count(0) > 100 and codes.count(2) > 0 and codes.count(3) > 0
