"""Every code block of README.md and docs/**/*.md runs as written.

A page is read top to bottom the way a reader follows it, from the root of a checkout (a
temporary directory whose entries link to this repository's, so files the page writes stay out of
the tree):

- ``python`` blocks run in one namespace per page (a later block may use an earlier one's names);
- ``bash`` blocks run in ``bash -eu`` with ``uvms-qp`` and ``python`` meaning this checkout's
  command line and interpreter; they must exit 0 without a traceback;
- ``toml`` blocks are scenarios (loaded and run for a few steps), sweep files (loaded and
  checked) or model files (loaded and built); a block whose first line is a comment naming a
  file (``# my_rov.toml``) is also written to that file for the blocks after it.

A block is skipped only when the line before its fence is ``<!-- fragment -->`` (a piece of a
larger whole, e.g. an install command or a table to paste into another file); a block in another
language must be marked so. The convention is documented in docs/developer.md.
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
import tomllib
from dataclasses import dataclass
from pathlib import Path

import matplotlib.pyplot as plt
import pytest

from uvms_qp.model import load_model, model_names, unregister_model
from uvms_qp.sim import simulate
from uvms_qp.sim.model_file import register_model_file
from uvms_qp.sim.scenario import load_scenario, scenario_from_dict
from uvms_qp.sweep import load_sweep, sweep_from_dict

ROOT = Path(__file__).resolve().parents[2]
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").rglob("*.md"))]
FRAGMENT = "<!-- fragment -->"
RUNS = ("python", "bash", "toml")
_FENCE = re.compile(r"^(\s*)```(\S*)\s*$")
_NEVER_RUN = re.compile(r"pip install|pytest")
_FILE_NAME = re.compile(r"^#\s*([\w.-]+\.toml)\s*$")


@dataclass(frozen=True)
class Block:
    """One fenced code block: its language, text (indentation removed) and where it is."""

    page: Path
    line: int
    language: str
    text: str
    fragment: bool

    @property
    def where(self) -> str:
        return f"{self.page.relative_to(ROOT)}:{self.line}"


def code_blocks(page: Path, text: str | None = None) -> list[Block]:
    """The fenced blocks of a Markdown page, in order."""
    lines = (page.read_text() if text is None else text).splitlines()
    blocks: list[Block] = []
    k = 0
    while k < len(lines):
        opening = _FENCE.match(lines[k])
        if not opening:
            k += 1
            continue
        indent, language = opening.groups()
        previous = next((s.strip() for s in reversed(lines[:k]) if s.strip()), "")
        end = k + 1
        while end < len(lines) and lines[end].strip() != "```":
            end += 1
        assert end < len(lines), f"{page}:{k + 1}: unclosed code block"
        body = [s[len(indent):] if s.startswith(indent) else s.lstrip() for s in lines[k + 1:end]]
        blocks.append(Block(page, k + 1, language, "\n".join(body) + "\n", previous == FRAGMENT))
        k = end + 1
    return blocks


def _sandbox(directory: Path) -> Path:
    """A checkout-like directory: links to the repository's entries, plus shims on PATH."""
    for entry in ROOT.iterdir():
        if entry.name not in {".git", "out"} and not entry.name.startswith("."):
            (directory / entry.name).symlink_to(entry)
    bin_dir = directory / ".bin"
    bin_dir.mkdir()
    for name, command in (("uvms-qp", f'"{sys.executable}" -m uvms_qp'),
                          ("python", f'"{sys.executable}"')):
        shim = bin_dir / name
        shim.write_text(f'#!/bin/sh\nexec {command} "$@"\n')
        shim.chmod(0o755)
    return bin_dir


def _run_bash(block: Block, cwd: Path, bin_dir: Path) -> None:
    assert not _NEVER_RUN.search(block.text), (
        f"{block.where}: a block that installs or runs the test suite is marked {FRAGMENT}")
    env = dict(os.environ, MPLBACKEND="Agg", PYTHONPATH=str(ROOT), COLUMNS="100",
               PATH=f"{bin_dir}{os.pathsep}{os.environ.get('PATH', '')}")
    proc = subprocess.run(["bash", "-eu", "-c", block.text], cwd=cwd, env=env,
                          capture_output=True, text=True, timeout=900, check=False)
    assert proc.returncode == 0, f"{block.where}: exit {proc.returncode}\n{proc.stderr[-3000:]}"
    assert "Traceback" not in proc.stderr, f"{block.where}:\n{proc.stderr[-3000:]}"


def _run_toml(block: Block, cwd: Path) -> None:
    data = tomllib.loads(block.text)
    first = block.text.splitlines()[0]
    named = _FILE_NAME.match(first)
    path = None
    if named:
        path = cwd / named.group(1)
        path.write_text(block.text)
    if "levels" in data:
        scenario = (load_scenario(path) if path else
                    scenario_from_dict(data, source=block.page))  # paths from the page's folder
        result = simulate(scenario, duration=min(scenario.duration, 3 * scenario.dt))
        assert result.metrics()["nan_steps"] == 0, block.where
    elif "scenario" in data and "runs" in data:  # a sweep file: checked as `uvms-qp sweep` does
        spec = load_sweep(path) if path else sweep_from_dict(data, source=block.page)
        assert spec.runs >= 1, block.where
    elif ("urdf" in data or "dh" in data) and path is not None:
        assert load_model(register_model_file(path)).nv > 0   # what --model-path does
    else:
        pytest.fail(f"{block.where}: a TOML block is a scenario, a sweep file or a model file "
                    f"named on its first line; anything else is marked {FRAGMENT}")


def _anchors(page: Path) -> set[str]:
    """GitHub's anchors of a page's headings."""
    headings = re.findall(r"^#+ (.+)$", page.read_text(), flags=re.MULTILINE)
    return {re.sub(r"[^\w\- ]", "", h.strip().lower()).replace(" ", "-") for h in headings}


@pytest.mark.parametrize("page", PAGES, ids=[str(p.relative_to(ROOT)) for p in PAGES])
def test_relative_links_and_anchors_resolve(page):
    text = re.sub(r"```.*?```", "", page.read_text(), flags=re.DOTALL)
    for target in re.findall(r"\]\(([^)\s]+)\)", text):
        if re.match(r"[a-z]+:", target):
            continue
        path, _, anchor = target.partition("#")
        file = (page.parent / path).resolve() if path else page
        assert file.exists(), f"{page.relative_to(ROOT)}: {target} does not exist"
        if anchor and file.suffix == ".md":
            assert anchor in _anchors(file), f"{page.relative_to(ROOT)}: no heading #{anchor}"


@pytest.mark.parametrize("page", PAGES, ids=[str(p.relative_to(ROOT)) for p in PAGES])
def test_papers_are_cited_by_authors_and_year(page):
    text = page.read_text()
    assert not re.findall(r"\w+_[0-9a-f]{16}(?:\.txt)?", text), "a paper cited by file name"
    assert not re.findall(r"[Pp]apers? 00[0-3]\b|\b00[0-3] (?:Eq|Section)", text), (
        "a paper cited by its number: use authors and year (docs/references.md)")


def test_a_fragment_is_marked_and_the_rest_is_found():
    text = ("x\n\n```python\nprint(1)\n```\n" f"{FRAGMENT}\n```python\nundefined\n```\n"
            "- item:\n\n  ```toml\n  a = 1\n  ```\n")
    blocks = code_blocks(ROOT / "x.md", text)
    assert [(b.line, b.language, b.fragment) for b in blocks] == [
        (3, "python", False), (7, "python", True), (12, "toml", False)]
    assert blocks[2].text == "a = 1\n"


def test_every_page_with_code_is_run():
    pages = {p for p in PAGES if code_blocks(p)}
    assert {ROOT / "README.md", ROOT / "docs" / "own_robot.md"} <= pages
    assert len(pages) >= 8


@pytest.mark.parametrize("page", PAGES, ids=[str(p.relative_to(ROOT)) for p in PAGES])
def test_page_code_runs(page, tmp_path, monkeypatch):
    blocks = [b for b in code_blocks(page) if not b.fragment]
    for block in blocks:
        assert block.language in RUNS, (
            f"{block.where}: a ```{block.language} block does not run; give it one of {RUNS} "
            f"or mark it {FRAGMENT}")
    if not blocks:
        return
    bin_dir = _sandbox(tmp_path)
    monkeypatch.chdir(tmp_path)
    registered = set(model_names())
    namespace: dict = {"__name__": "__docs__"}
    try:
        for block in blocks:
            if block.language == "python":
                exec(compile("\n" * block.line + block.text, str(page), "exec"), namespace)
            elif block.language == "bash":
                _run_bash(block, tmp_path, bin_dir)
            else:
                _run_toml(block, tmp_path)
    finally:
        plt.close("all")
        for name in set(model_names()) - registered:
            unregister_model(name)
