"""CITATION.cff: valid Citation File Format 1.2.0, and in step with the package and README."""

import re
from pathlib import Path

import yaml

import comgrasp_pin

ROOT = Path(__file__).resolve().parents[1]


def _cff() -> dict:
    return yaml.safe_load((ROOT / "CITATION.cff").read_text(encoding="utf-8"))


def test_the_citation_file_has_the_formats_required_keys():
    """CFF 1.2.0 requires cff-version, message, title and authors (each a person with
    family-names or an entity with a name); a preferred citation requires type, title and
    authors too."""
    cff = _cff()
    assert cff["cff-version"] == "1.2.0"
    for key in ("message", "title", "authors"):
        assert cff[key], key
    for who in [*cff["authors"], *cff["preferred-citation"]["authors"]]:
        assert who.get("name") or who.get("family-names"), who
    for key in ("type", "title", "authors"):
        assert cff["preferred-citation"][key], key


def test_the_citation_file_agrees_with_the_package_and_the_readme():
    """Its version is the package's, its licence pyproject's, and its preferred citation the
    paper the README cites (title, authors in order, the arXiv identifier)."""
    cff = _cff()
    assert cff["version"] == comgrasp_pin.__version__
    pyproject = (ROOT / "pyproject.toml").read_text(encoding="utf-8")
    assert re.search(rf'^license = "{re.escape(cff["license"])}"', pyproject, flags=re.M)
    readme = re.sub(r"\s+", " ", (ROOT / "README.md").read_text(encoding="utf-8").replace(">", ""))
    paper = cff["preferred-citation"]
    assert re.sub(r"\s+", " ", paper["title"]).strip() in readme
    names = ", ".join(f"{a['given-names']} {a['family-names']}" for a in paper["authors"])
    assert names in readme
    assert paper["identifiers"][0]["value"] in readme
