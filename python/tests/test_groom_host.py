"""The host on a skinned, walking character of our own making
(scripts/make_character.py): feathers follow the skeleton (head down the
trunk, down each limb), in harmony with their neighbours and collision-free
in every frame; the front-most-vertex source it replaces makes a star."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from conftest import REPO, run_host


@pytest.fixture(scope="module")
def character(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("character") / "character.glb"
    subprocess.run([sys.executable, str(REPO / "scripts" / "make_character.py"), str(out)], check=True)
    return out


def dress(host: str, model: Path, tmp: Path, *extra: str) -> dict:
    report = tmp / "report.json"
    run = run_host(host, str(model), "--feathers", "2000", "--frames", "8", "--validate", "every",
                   "--report", str(report), *extra)
    assert run.returncode == 0, run.stderr
    return json.loads(report.read_text())


def test_the_characters_coat_follows_its_skeleton(host, character, tmp_path) -> None:
    for seed in ("1", "5"):
        r = dress(host, character, tmp_path, "--seed", seed)
        assert r["config"]["flow_from"] == "skeleton" and r["config"]["skeleton_joints"] == 16
        s = r["summary"]
        assert s["max_intersecting_pairs"] == 0 and s["max_body_penetrations"] == 0
        assert s["max_discord_percent"] <= 1.0, s
        # One source or sink at each capsule's ends at most (each capsule is
        # closed, so its field turns at least once), no whorls elsewhere.
        assert r["sampling"]["field_singularities"] <= 2 * 10 + 4, r["sampling"]
    front = dress(host, character, tmp_path, "--seed", "1", "--skeleton-flow", "off")
    assert front["config"]["flow_from"] == "flow_source"
    assert front["summary"]["max_discord_percent"] > 2 * s["max_discord_percent"], (front["summary"], s)


def test_painted_types_and_layers_dress_the_character_without_crossings(host, character, tmp_path) -> None:
    r = dress(host, character, tmp_path, "--type-map", "_FEATHER_TYPE", "--feather-types", "feathers,scales",
              "--layer-map", "_LAYER")
    assert r["config"]["type_map"] == "_FEATHER_TYPE:0" and r["config"]["layer_map"] == "_LAYER:0"
    s = r["summary"]
    assert s["max_intersecting_pairs"] == 0 and s["max_body_penetrations"] == 0, s
    assert s["max_discord_percent"] <= 1.0, s
    bad = subprocess.run([host, str(character), "--frames", "0", "--type-map", "_FEATHER_TYPE", "--feather-types", "feathers,gills"],
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    assert bad.returncode == 2 and "--feather-types gills" in bad.stderr
