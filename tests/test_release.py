"""Ready to cite and depend on: the licence the package states is the one shipped, the version is
written once (``shoal.__version__``) and everything that states one reads it: the package's
metadata, ``CITATION.cff``, the changelog's newest entry and the provenance of every output."""

from __future__ import annotations

import json
import re
import tomllib
from importlib import metadata
from pathlib import Path

import yaml

import shoal
from shoal.app.cli import main

ROOT = Path(__file__).resolve().parents[1]


def test_the_licence_stated_is_the_one_shipped():
    project = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))["project"]
    assert project["license"] == "MIT" and project["license-files"] == ["LICENSE"]
    text = (ROOT / "LICENSE").read_text(encoding="utf-8")
    assert text.startswith("MIT License") and "Permission is hereby granted, free of charge" in text
    assert metadata.metadata("shoal")["License-Expression"] == "MIT"


def test_the_version_is_written_once_and_read_everywhere():
    project = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))
    assert "version" not in project["project"] and project["project"]["dynamic"] == ["version"]
    assert project["tool"]["setuptools"]["dynamic"]["version"] == {"attr": "shoal.__version__"}
    assert re.fullmatch(r"\d+\.\d+\.\d+", shoal.__version__)
    assert metadata.version("shoal") == shoal.__version__, "reinstall: pip install -e ."
    citation = yaml.safe_load((ROOT / "CITATION.cff").read_text(encoding="utf-8"))
    assert citation["version"] == shoal.__version__ and citation["license"] == "MIT"
    newest = re.search(r"^## \[(\d+\.\d+\.\d+)\]", (ROOT / "CHANGELOG.md").read_text(encoding="utf-8"), re.M)
    assert newest is not None and newest.group(1) == shoal.__version__


def test_the_citation_names_shoal_and_both_theses():
    citation = yaml.safe_load((ROOT / "CITATION.cff").read_text(encoding="utf-8"))
    assert citation["cff-version"] == "1.2.0" and citation["type"] == "software" and citation["authors"]
    theses = {r["authors"][0]["family-names"]: r for r in citation["references"]}
    assert set(theses) == {"Rossides", "Mai"} and all(r["type"] == "thesis" for r in theses.values())
    assert (theses["Rossides"]["year"], theses["Mai"]["year"]) == (2022, 2018)
    assert theses["Rossides"]["title"] == ("Cooperative Autonomous Marine Vehicles for Adaptive Passive Acoustic "
                                           "Monitoring")
    assert theses["Mai"]["title"].startswith("Simultaneous Localisation and Optimisation")


def test_a_runs_provenance_is_the_package_version(tmp_path, capsys):
    assert main(["run", "default", "--steps", "2", "--out", str(tmp_path / "r")]) == 0
    capsys.readouterr()
    assert json.loads((tmp_path / "r" / "run.json").read_text())["shoal_version"] == shoal.__version__


def test_the_classifiers_say_what_it_is():
    classifiers = metadata.metadata("shoal").get_all("Classifier") or []
    assert "Typing :: Typed" in classifiers and "Intended Audience :: Science/Research" in classifiers
    assert any(c.startswith("Development Status ::") for c in classifiers)
    assert not any(c.startswith("License ::") for c in classifiers)  # (the licence is the SPDX expression)
