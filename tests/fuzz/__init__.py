"""Fuzzing mzc's readers: the targets and worker (readers.py), an atheris harness for long runs
(atheris_readers.py, README.md); tests/test_fuzz_readers.py runs them in the suite."""
