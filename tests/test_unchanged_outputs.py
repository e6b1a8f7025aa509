"""Every command's output bytes on the samples and the faces equal the committed reference.

The reference (tests/data/golden-outputs.json, made by tests/golden.py) was written before
the code was reorganised into its packages; a move that changes one byte fails here.
"""

import json

import pytest

from golden import FACES, REFERENCE, all_digests


def test_every_output_is_byte_identical_to_the_reference():
    reference = json.loads(REFERENCE.read_text())
    measured = all_digests()
    if not FACES.is_dir():
        reference = {case: value for case, value in reference.items() if case in measured}
    changed = sorted(case for case in reference if measured.get(case) != reference[case])
    assert not changed, f"{len(changed)} output(s) changed: {changed[:10]}"
    assert len(measured) == len(reference)


def test_the_reference_covers_every_command_and_codec():
    cases = json.loads(REFERENCE.read_text())
    for word in ("sample", "slice", "encode", "decode", "densify", "triangulate", "info", "diff"):
        assert any(word in case for case in cases), word
    if not FACES.is_dir():
        pytest.skip("shared faces absent")
    assert sum(case.endswith(": slice") for case in cases) == 5 + 13
