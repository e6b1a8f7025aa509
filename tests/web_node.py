"""What the tests of web/ share: its folder, node (they skip without it) and a run of an ES module
in web/ on JSON cases."""

import json
import shutil
import subprocess

import pytest

from codec_contract import FIXTURES

WEB = FIXTURES.parents[1] / "web"
NODE = shutil.which("node")
needs_node = pytest.mark.skipif(NODE is None, reason="node is not installed")


def node_json(script, cases, timeout=300):
    """The JSON that ``script`` (an ES module run in web/) writes for ``cases`` given on stdin."""
    run = subprocess.run([NODE, "--input-type=module", "-e", script], input=json.dumps(cases).encode(),
                         capture_output=True, cwd=WEB, timeout=timeout)
    assert run.returncode == 0, run.stderr.decode()
    return json.loads(run.stdout)
