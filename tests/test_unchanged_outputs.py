"""Every command's output bytes on the samples, the fixtures and the faces equal the committed
reference, on this machine and with numpy's AVX-512 and AVX2 loops switched off.

The reference (tests/data/golden-outputs.json, made by tests/golden.py) was written before
the code was reorganised into its packages; a move that changes one byte fails here. numpy
picks SIMD loops by the CPU when it starts (``NPY_DISABLE_CPU_FEATURES`` switches them off)
and OpenBLAS its kernels (``OPENBLAS_CORETYPE`` picks one): mzc computes its outputs with
neither (spec/arithmetic.md), and the subprocess runs here hold it to that on any machine,
as an AVX2 machine (AVX-512 off, OpenBLAS's Haswell kernels) and an SSE4 one (AVX2 off,
Nehalem's) would run it.
"""

import importlib
import json
import os
import platform
import subprocess
import sys

import numpy as np
import pytest

from golden import FACES, REFERENCE, all_digests

GOLDEN = REFERENCE.parents[1] / "golden.py"
UMATH = "numpy._core._multiarray_umath" if np.__version__ >= "2" else "numpy.core._multiarray_umath"
OTHER_MACHINES = {   # case: (the feature it switches off, numpy's dispatch targets at or above it, OpenBLAS's core)
    "AVX-512 off": ("AVX512F", lambda target: target == "X86_V4" or target.startswith("AVX512"), "Haswell"),
    "AVX2 off": ("AVX2", lambda target: target in ("X86_V3", "X86_V4", "AVX2", "FMA3") or target.startswith("AVX512"),
                 "Nehalem"),
}


def reference_for(measured):
    """The committed digests of the cases ``measured`` can hold (the faces' only when they are here)."""
    reference = json.loads(REFERENCE.read_text())
    if not FACES.is_dir():
        reference = {case: value for case, value in reference.items() if case in measured}
    return reference


def changed_cases(measured):
    """The cases whose output differs from the reference, and whether every case was measured."""
    reference = reference_for(measured)
    return sorted(case for case in reference if measured.get(case) != reference[case]), len(measured) == len(reference)


def test_every_output_is_byte_identical_to_the_reference():
    changed, complete = changed_cases(all_digests())
    assert not changed, f"{len(changed)} output(s) changed: {changed[:10]}"
    assert complete


def test_the_reference_covers_every_command_and_codec():
    cases = json.loads(REFERENCE.read_text())
    for word in ("sample", "slice", "encode", "decode", "densify", "triangulate", "info", "diff", "fixture"):
        assert any(word in case for case in cases), word
    if not FACES.is_dir():
        pytest.skip("shared faces absent")
    assert sum(case.endswith(": slice") for case in cases) == 5 + 13


def numpy_cpu():
    """(numpy's dispatch targets, the features it uses on this CPU)."""
    umath = importlib.import_module(UMATH)
    return list(umath.__cpu_dispatch__), {name for name, present in umath.__cpu_features__.items() if present}


def switched_off_environment(case):
    """(environment switching numpy's loops at and above the case's feature off and OpenBLAS to
    its kernels, the targets switched off) or a pytest.skip saying why this machine cannot."""
    feature, above, core = OTHER_MACHINES[case]
    if platform.machine().lower() not in ("x86_64", "amd64"):
        pytest.skip(f"{case}: numpy's x86 features do not exist on {platform.machine()}")
    targets, present = numpy_cpu()
    if feature not in present:
        pytest.skip(f"{case}: numpy does not use {feature} here (the CPU lacks it, or NPY_DISABLE_CPU_FEATURES "
                    "switched it off already), so it runs none of those loops: nothing more to switch off")
    off = [target for target in targets if above(target)]
    return {**os.environ, "NPY_DISABLE_CPU_FEATURES": " ".join(off), "OPENBLAS_CORETYPE": core}, off


@pytest.fixture(scope="module")
def other_machines():
    """{case: (its finished subprocess, the targets it switched off)} or the skip message: the golden
    digests computed with numpy's loops switched off, both cases run at once."""
    started = {}
    for case in OTHER_MACHINES:
        try:
            environment, off = switched_off_environment(case)
        except pytest.skip.Exception as skipped:
            started[case] = str(skipped)
            continue
        check = f"import {UMATH} as m; assert not any(m.__cpu_features__[t] for t in {off!r})"
        command = [sys.executable, "-c", f"{check}; import runpy, sys; sys.argv = ['golden', '--print']; "
                                         f"runpy.run_path({str(GOLDEN)!r}, run_name='__main__')"]
        started[case] = (subprocess.Popen(command, env=environment, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                                          cwd=GOLDEN.parent), off)
    return {case: (run if isinstance(run, str) else (run[0], run[0].communicate(), run[1]))
            for case, run in started.items()}


@pytest.mark.parametrize("case", OTHER_MACHINES)
def test_outputs_are_the_same_bytes_with_numpys_simd_loops_switched_off(other_machines, case):
    """What an AVX2 machine and an SSE4 one would compute: the same bytes as the reference."""
    run = other_machines[case]
    if isinstance(run, str):
        pytest.skip(run)
    process, (out, err), off = run
    if b"cannot disable" in err or b"baseline" in err:
        pytest.skip(f"{case}: this numpy cannot switch off {off} ({err.decode().strip().splitlines()[-1]})")
    assert process.returncode == 0, err.decode()[-2000:]
    changed, complete = changed_cases(json.loads(out))
    assert not changed, f"{case} ({' '.join(off)}): {len(changed)} output(s) differ: {changed[:10]}"
    assert complete
