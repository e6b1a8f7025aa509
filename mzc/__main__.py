"""Run mzc as ``python -m mzc``."""

from mzc.cli import main

main()
