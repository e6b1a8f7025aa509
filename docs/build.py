"""Build mzc's documentation site with MkDocs, from the sources the repository already has:

- the guide: README.md, as it is;
- the command-line reference: each command's ``--help``, as click prints it;
- the API reference: the signature and docstring of every public name of ``import mzc``;
- the format specifications: spec/*.md.

The pages are generated into a temporary folder, so each has one home in the repository and
none is a copy to keep in step. MkDocs builds in strict mode: a warning (a broken link, a page
left out of the navigation) fails the build.

    python docs/build.py [SITE_DIR]        # default: site/
"""

import inspect
import subprocess
import sys
import tempfile
from pathlib import Path

import click

import mzc
from mzc.cli import COMMANDS, group

REPO = Path(__file__).resolve().parents[1]


def cli_page():
    """Markdown of every command's --help (a group's subcommands too), in the order ``mzc --help`` lists them."""
    sections = ["# Command-line reference", "", help_block(group, "mzc")]
    for name in COMMANDS:
        command = group.get_command(click.Context(group), name)
        sections += [f"## mzc {name}", "", help_block(command, f"mzc {name}")]
        for sub in getattr(command, "commands", {}).values():
            sections += [f"### mzc {name} {sub.name}", "", help_block(sub, f"mzc {name} {sub.name}")]
    return "\n".join(sections)


def help_block(command, path):
    """A command's --help text as a fenced block."""
    context = click.Context(command, info_name=path, terminal_width=100)
    return f"```text\n{command.get_help(context)}\n```\n"


def api_page():
    """Markdown of the public API: each name of ``mzc.__all__`` with its signature and docstring,
    a class's public methods and properties below it."""
    sections = ["# Python API", "", inspect.getdoc(mzc), ""]
    for name in mzc.__all__:
        if name.startswith("__"):
            continue
        item = getattr(mzc, name)
        sections += [f"## mzc.{name}", "", entry(name, item)]
        if inspect.isclass(item):
            for member_name, member in vars(item).items():
                if not member_name.startswith("_") and inspect.getdoc(member) and not isinstance(member, type):
                    sections += [f"### {name}.{member_name}", "", entry(member_name, member)]
    return "\n".join(sections)


def entry(name, item):
    """A name's signature (for what has one) and its docstring."""
    target = item.fget if isinstance(item, property) else item
    try:
        signature = f"```python\n{name}{inspect.signature(target)}\n```\n\n" if callable(target) else ""
    except (TypeError, ValueError):
        signature = ""
    return signature + (inspect.getdoc(target) or "") + "\n"


def sources(folder):
    """Write the pages and mkdocs.yml into ``folder``; the config's path."""
    docs = folder / "docs"
    (docs / "spec").mkdir(parents=True)
    (docs / "index.md").write_text((REPO / "README.md").read_text(encoding="utf-8"), encoding="utf-8")
    (docs / "cli.md").write_text(cli_page(), encoding="utf-8")
    (docs / "api.md").write_text(api_page(), encoding="utf-8")
    specs = sorted((REPO / "spec").glob("*.md"))
    for spec in specs:
        (docs / "spec" / spec.name).write_text(spec.read_text(encoding="utf-8"), encoding="utf-8")
    nav = "\n".join(f"      - spec/{spec.name}" for spec in specs)
    config = folder / "mkdocs.yml"
    config.write_text(f"""site_name: mzc {mzc.__version__}
docs_dir: docs
theme: mkdocs
nav:
  - Guide: index.md
  - Command line: cli.md
  - Python API: api.md
  - Formats:
{nav}
""", encoding="utf-8")
    return config


def build(site):
    """Build the site into ``site`` (strict: any MkDocs warning fails); MkDocs' exit status."""
    with tempfile.TemporaryDirectory(prefix="mzc-docs-") as folder:
        config = sources(Path(folder))
        return subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict", "--quiet",
                               "-f", str(config), "-d", str(Path(site).resolve())]).returncode


if __name__ == "__main__":
    sys.exit(build(sys.argv[1] if len(sys.argv) > 1 else REPO / "site"))
