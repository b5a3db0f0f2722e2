"""Write softtip's public home (its repository URL) into every file that names it.

softtip has no public home yet, so no file names one: the README's links are relative (they
work in a clone, in the sdist and on any git host's page of the repository), ``pyproject.toml``
has no ``[project.urls]``, ``CITATION.cff`` no ``repository-code`` and ``ros/package.xml`` no
``<url>``. Before the first upload to a package index (docs/contributing.md, "Releases"), run

    python scripts/set_home.py https://github.com/OWNER/REPO [--ref main] [--email MAINTAINER@HOST]

which writes ``[project.urls]`` (the one place the home is declared), the citation file's
``repository-code``, the ROS 2 package's ``<url>`` elements (and its maintainer's email), and
turns the README's relative links into absolute ones under the home (images through the
host's raw-file address), because a package index shows the README away from the repository.
Running it again with the same arguments changes nothing. ``tests/test_home.py`` checks that
every file agrees with ``[project.urls]``; ``tests/test_release.py`` builds a release after
running this script on a copy of the tree.
"""

from __future__ import annotations

import argparse
import re
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def bases(home: str, ref: str) -> tuple[str, str]:
    """The address of a file's page and of its raw bytes under ``home`` at ``ref`` (GitHub and
    GitLab layouts; another host needs ``--blob`` and ``--raw``)."""
    m = re.fullmatch(r"https://(github\.com|gitlab\.com)/([^/\s]+)/([^/\s]+?)/?", home)
    if m is None:
        raise SystemExit(f"{home}: not a https://github.com/OWNER/REPO or https://gitlab.com/OWNER/REPO "
                         "address; give the file bases with --blob and --raw")  # fmt: skip
    host, owner, repo = m.groups()
    if host == "github.com":
        return f"{home}/blob/{ref}/", f"https://raw.githubusercontent.com/{owner}/{repo}/{ref}/"
    return f"{home}/-/blob/{ref}/", f"{home}/-/raw/{ref}/"


def set_pyproject(text: str, home: str, blob: str) -> str:
    urls = (
        "[project.urls]\n"
        f'Homepage = "{home}"\n'
        f'Documentation = "{blob}docs/index.md"\n'
        f'Repository = "{home}"\n'
        f'Issues = "{home}/issues"\n'
        f'Changelog = "{blob}CHANGELOG.md"\n\n'
    )
    text = re.sub(r"\[project\.urls\]\n(?:[^\[\n][^\n]*\n|\n)*", "", text)
    head, sep, tail = text.partition("[project.scripts]")
    if not sep:
        raise SystemExit("pyproject.toml: no [project.scripts] table to put [project.urls] before")
    return head + urls + sep + tail


def set_citation(text: str, home: str) -> str:
    text = re.sub(r"^repository-code: .*\n", "", text, flags=re.M)
    text, n = re.subn(r"^(license: .*\n)", rf'\1repository-code: "{home}"\n', text, count=1, flags=re.M)
    if n != 1:
        raise SystemExit("CITATION.cff: no top-level license line to put repository-code after")
    return text


def set_package_xml(text: str, home: str, email: str | None) -> str:
    text = re.sub(r"^  <url type=\"[a-z]+\">.*</url>\n", "", text, flags=re.M)
    urls = (f'  <url type="website">{home}</url>\n  <url type="repository">{home}</url>\n'
            f'  <url type="bugtracker">{home}/issues</url>\n')  # fmt: skip
    text, n = re.subn(r"^(  <license>.*</license>\n)", lambda m: m.group(1) + urls, text, count=1, flags=re.M)
    if n != 1:
        raise SystemExit("ros/package.xml: no <license> line to put the <url> elements after")
    if email is not None:
        text = re.sub(r'(<maintainer email=")[^"]*(")', rf"\g<1>{email}\g<2>", text)
    return text


def set_setup_py(text: str, email: str | None) -> str:
    return text if email is None else re.sub(r'(maintainer_email=")[^"]*(")', rf"\g<1>{email}\g<2>", text)


def set_readme(text: str, blob: str, raw: str) -> str:
    """Relative Markdown links ``[text](path)`` under ``blob``, images ``![alt](path)`` under ``raw``."""

    def absolute(m: re.Match) -> str:
        bang, label, target = m.groups()
        if re.match(r"[a-z][a-z0-9+.-]*:|#", target):  # already absolute, or an anchor in the README
            return m.group(0)
        return f"{bang}[{label}]({(raw if bang else blob) + target.removeprefix('./')})"

    return re.sub(r"(!?)\[([^\]]*)\]\(([^)\s]+)\)", absolute, text)


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("home", help="the repository's address, e.g. https://github.com/OWNER/REPO")
    parser.add_argument("--ref", default="main", help="the branch or tag the README's links point into (default main)")
    parser.add_argument("--email", help="the ROS 2 package maintainer's email (package.xml, ros/setup.py)")
    parser.add_argument("--blob", help="the address of a file's page, ending in / (a host other than GitHub or GitLab)")
    parser.add_argument("--raw", help="the address of a file's raw bytes, ending in /")
    parser.add_argument("--root", type=Path, default=ROOT, help="the source tree (default: this script's)")
    args = parser.parse_args(argv)
    home = args.home.rstrip("/")
    blob, raw = (args.blob, args.raw) if args.blob and args.raw else bases(home, args.ref)
    edits = {
        "pyproject.toml": lambda t: set_pyproject(t, home, blob),
        "CITATION.cff": lambda t: set_citation(t, home),
        "ros/package.xml": lambda t: set_package_xml(t, home, args.email),
        "ros/setup.py": lambda t: set_setup_py(t, args.email),
        "README.md": lambda t: set_readme(t, blob, raw),
    }
    for name, edit in edits.items():
        path = args.root / name
        old = path.read_text(encoding="utf-8")
        new = edit(old)
        if new != old:
            path.write_text(new, encoding="utf-8")
            print(f"set_home: {name}", file=sys.stderr)


if __name__ == "__main__":
    main()
