"""Levels are numbered from 0 everywhere a user reads them: docs, examples, docstrings, scenario
files, summaries and figures (the figures' residual labels: ``tests/unit/sim/test_figures.py``).

Two rules on the text: no 1-based notation (``L_1 > ... > L_p``, ``A_1 ; ... ; A_p``), and a
text that names a level by a number above 0 names level 0 too (an enumeration starts at 0).
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from tests.docs.test_citations import ROOT, _tracked_files
from uvms_qp import Level, Rows, Stack, solve_hierarchy
from uvms_qp.tasks import EndEffectorTask, PostureTask

#: Notation that counts levels from 1.
ONE_BASED = re.compile(r"\bL_?1 > \.\.\. > L_?p\b|\b[A-Za-z]+_1 ; \.\.\. ; [A-Za-z]+_p\b"
                       r"|\blevels? 1 ?(?:\.\.|to) ?p\b")
#: "level N" naming a level (not "level 21 us", a duration of one level's work).
NAMED = re.compile(r"\b[Ll]evel (\d+)\b(?![.\d]| ?(?:us|ms|s|k)\b)")
SCOPE = ("uvms_qp", "docs", "examples", "benchmarks", "README.md")
TEXTS = (".md", ".py", ".toml", ".txt")


def _offences(text: str) -> list[str]:
    found = [m.group(0) for m in ONE_BASED.finditer(text)]
    named = {int(n) for n in NAMED.findall(text)}
    if named and 0 not in named:
        found.append(f"names level(s) {sorted(named)} but never level 0")
    return found


def test_the_rules_tell_1_based_numbering_from_0_based():
    assert _offences("Levels ``L_1 > ... > L_p`` of rows")
    assert _offences("A = [ I ; A_H ; A_1 ; ... ; A_p ]")
    assert _offences("level 1 the tool, level 2 the vehicle")
    assert _offences("# level 1: x1 + x2 = 2") and not _offences("# level 0: x = 1\n# level 1: ...")
    assert not _offences("Levels ``L_0 > ... > L_(p-1)``; the unmet level 21 us, level 20.6 us")
    assert not _offences("Levels L0 > L1 > ... > L(p-1), numbered from 0")


def test_docs_examples_docstrings_and_scenarios_number_levels_from_0():
    scope = [p for p in _tracked_files()
             if p.suffix in TEXTS and p.relative_to(ROOT).parts[0] in SCOPE]
    assert any(p.name == "solver.md" for p in scope)
    offences = {str(p.relative_to(ROOT)): found for p in scope
                if (found := _offences(Path(p).read_text(errors="replace")))}
    assert offences == {}


def test_summaries_number_levels_from_0(models):
    result = solve_hierarchy([[Rows.equality([[1.0, -1.0]], [0.4])], [([[1.0, 1.0]], [2.0])]],
                             lower=[-1.0, -1.0], upper=[1.0, 1.0])
    lines = result.summary().splitlines()
    assert [line.split(":")[0].strip() for line in lines[1:3]] == ["level 0", "level 1"]
    model = models["bluerov2_heavy_alpha5"]
    stack = Stack([Level(EndEffectorTask(position=[0.5, 0.1, 0.0]), name="tool"),
                   Level(PostureTask(posture=list(np.zeros(model.n_joints))))])
    described = [line for line in stack.describe().splitlines() if line.startswith("level")]
    assert described == ["level 0 (tool)", "level 1"]
