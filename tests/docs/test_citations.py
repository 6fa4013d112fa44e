"""Papers are cited by authors and year, never by the name of their text copy or a bare number.

The rule of docs/references.md: "Soylu et al. (2007), Eq. (21)", not the file the text was read
from (``000_<16 hex digits>.txt``) nor "paper 000". The short numbers stay only inside names
(scenarios such as ``paper000_quintic``, figure files, the pages of docs/papers/), which are
identifiers, not citations.
"""

from __future__ import annotations

import re
import subprocess
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
SCOPE = ("uvms_qp", "docs", "tests", "benchmarks", "examples", "README.md")
SELF = Path(__file__).resolve()

#: A paper text's file name, or a paper called by its number in prose ("paper 002's").
FORBIDDEN = re.compile(r"\b00[0-3]_[0-9a-f]{16}(?:\.txt)?|\bpapers? 00[0-3]\b", re.IGNORECASE)


def _tracked_files() -> list[Path]:
    """Files under SCOPE that git tracks (every file under SCOPE outside a git checkout)."""
    try:
        listed = subprocess.run(["git", "ls-files", "-z", "--", *SCOPE], cwd=ROOT,
                                capture_output=True, check=True).stdout
    except (OSError, subprocess.CalledProcessError):
        found = [p for name in SCOPE for p in [ROOT / name, *(ROOT / name).rglob("*")]]
        return [p for p in found if p.is_file() and "__pycache__" not in p.parts]
    return [ROOT / name for name in listed.decode().split("\0") if name]


def _offences(text: str) -> list[tuple[int, str]]:
    return [(number, match.group(0))
            for number, line in enumerate(text.splitlines(), start=1)
            for match in FORBIDDEN.finditer(line)]


def test_pattern_tells_citations_from_identifiers():
    file_name = "003_" + "229789978cc4b235" + ".txt"
    bad = [f"(``{file_name}, Eq. (20)``)", "paper 000's stretched arm", "Paper 002 (Nenchev)",
           "papers 001 and 003"]
    good = ["Soylu et al. (2007), Eq. (16)", "uvms-qp compare paper000_quintic",
            "`paper003_payload.png`", "docs/papers/001_santos.md", "test_paper002_pa10"]
    assert [text for text in bad if not _offences(text)] == []
    assert [text for text in good if _offences(text)] == []


def test_no_paper_cited_by_file_name_or_number():
    files = [p for p in _tracked_files() if p.resolve() != SELF and p.is_file()]
    assert len(files) > 100  # the scope was found, not an empty listing
    offences = []
    for path in files:
        try:
            text = path.read_text(encoding="utf-8")
        except UnicodeDecodeError:  # figures and other binary files
            continue
        offences += [f"{path.relative_to(ROOT)}:{number}: {found!r}"
                     for number, found in _offences(text)]
    assert offences == [], ("cite papers by authors and year (docs/references.md):\n"
                            + "\n".join(offences))
