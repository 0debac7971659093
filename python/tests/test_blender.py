"""The Blender add-on in a real, headless Blender: installed from its zip,
dressing a shape-key-animated UV sphere, checked collision-free by the
library's validation at each frame, baked, and one frame rendered."""

from __future__ import annotations

import importlib.util
import itertools
import json
import os
import shutil
import subprocess
import sys
import zipfile
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import plumage

from conftest import REPO, uv_sphere


def _blender() -> str:
    """The Blender program, or a counted skip."""
    blender = os.environ.get("PLUMAGE_BLENDER") or shutil.which("blender")
    if blender is None:
        pytest.skip("Blender is not installed (Debian: apt-get install blender)")
    return blender


def _addon_zip(tmp_path: Path) -> Path:
    """The add-on packed as Blender installs it."""
    addon_zip = tmp_path / "plumage_feathers.zip"
    with zipfile.ZipFile(addon_zip, "w") as z:
        for f in (REPO / "blender" / "plumage_feathers").rglob("*.py"):
            z.write(f, f.relative_to(REPO / "blender"))
    return addon_zip


def test_addon_dresses_steps_bakes_and_renders(tmp_path: Path) -> None:
    blender = _blender()
    addon_zip = _addon_zip(tmp_path)
    # Blender's own Python finds the package in the user scripts' modules folder
    scripts = tmp_path / "scripts"
    shutil.copytree(Path(plumage.__file__).parent, scripts / "modules" / "plumage", ignore=shutil.ignore_patterns("__pycache__"))
    out = tmp_path / "out"
    out.mkdir()
    env = {**os.environ, "BLENDER_USER_SCRIPTS": str(scripts), "BLENDER_USER_CONFIG": str(tmp_path / "config")}
    run = subprocess.run(
        [blender, "-b", "--factory-startup", "--python-exit-code", "1", "--python", str(REPO / "blender" / "tests" / "blender_run.py"),
         "--", str(addon_zip), str(out)],
        stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, env=env, timeout=540,
    )
    lines = [line for line in run.stdout.splitlines() if line.startswith("PLUMAGE_RESULT ")]
    assert run.returncode == 0 and lines, run.stdout[-4000:]
    result = json.loads(lines[-1][len("PLUMAGE_RESULT "):])

    assert 600 <= result["feathers"] <= 1000
    frames = result["frames"]
    assert [f["frame"] for f in frames] == [1, 2, 3, 4, 5, 6]
    # playing forward steps the system once per frame (frame 1 is the dressed pose)
    assert [f["frame_index"] for f in frames] == [0, 1, 2, 3, 4, 5]
    for f in frames:
        assert f["intersecting_pairs"] == 0 and f["body_penetrations"] == 0, f
        assert f["coverage"] > 0.5 and f["mesh_matches"], f
    # a jump seeks back and replays: the state after 2 steps, as playback left it
    assert result["scrub_back_frame_index"] == 2 and result["scrub_back_valid"]
    assert result["scrub_back_is_playback"] and result["scrub_forward_is_playback"] and result["scrub_mesh_matches"]
    assert result["cache_frames"] == [1, 2, 3, 4, 5, 6]
    assert result["cache_shape"][0] == 6 and result["cache_shape"][2] == 3
    assert result["cache_playback_matches"] and result["cache_playback_untouched"]
    scales = result["scales"]  # preset and segments set from the panel
    assert scales["feathers"] > result["feathers"] // 2 and scales["intersecting_pairs"] == 0 and scales["body_penetrations"] == 0, scales
    assert scales["vertices_per_feather"] > 4, scales  # three segments: more than the kite's four vertices
    png = Path(result["rendered"])
    assert png.is_file() and png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and png.stat().st_size > 10_000
    keep = os.environ.get("PLUMAGE_BLENDER_RENDER")
    if keep:
        shutil.copy(png, keep)


def test_addon_without_the_package_says_how_to_install_it(tmp_path: Path) -> None:
    blender = _blender()
    addon_zip = _addon_zip(tmp_path)
    # an empty user scripts folder: the package is not there
    env = {**os.environ, "BLENDER_USER_SCRIPTS": str(tmp_path / "scripts"), "BLENDER_USER_CONFIG": str(tmp_path / "config")}
    env.pop("PYTHONPATH", None)
    run = subprocess.run(
        [blender, "-b", "--factory-startup", "--python-exit-code", "1", "--python",
         str(REPO / "blender" / "tests" / "blender_missing_package.py"), "--", str(addon_zip)],
        stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, env=env, timeout=300,
    )
    lines = [line for line in run.stdout.splitlines() if line.startswith("PLUMAGE_RESULT ")]
    assert run.returncode == 0 and lines, run.stdout[-4000:]
    result = json.loads(lines[-1][len("PLUMAGE_RESULT "):])
    if not result["import_error"]:
        pytest.skip("plumage is importable in Blender's Python from elsewhere (a system-wide install)")
    assert "plumage Python package cannot be imported" in result["import_error"], result
    assert "pip install" in result["import_error"] and "BLENDER_USER_SCRIPTS" in result["import_error"], result
    assert "python -m plumage.blender_install" in result["import_error"], result
    # the operator's refusal carries the reason, not only "context is incorrect"
    assert "plumage Python package cannot be imported" in result["operator_error"], result


def _blender_json(blender: str, args: list, env: dict, timeout: int = 120, factory: bool = True) -> dict:
    """Runs Blender headless on a test script; its `PLUMAGE_RESULT {json}` line."""
    run = subprocess.run([blender, "-b", *(["--factory-startup"] if factory else []), "--python-exit-code", "1", *args],
                         stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, env=env, timeout=timeout)
    lines = [line for line in run.stdout.splitlines() if line.startswith("PLUMAGE_RESULT ")]
    assert run.returncode == 0 and lines, run.stdout[-4000:]
    return json.loads(lines[-1][len("PLUMAGE_RESULT "):])


def test_character_is_one_coat_baked_to_a_point_cache_that_plays_after_reopening(tmp_path: Path) -> None:
    """An armature with three bones, three skinned meshes (one a limb) and a mesh
    parented to a bone, animated over frames 1..20, dressed as one coat
    following the skeleton (the limb's feathers along its bone) with a
    painted layer group: valid at every
    frame, scrubbing 12, 3, 20, 12 shows playback, the .pc2 bake plays in a
    new Blender without the package, and the live system comes back from the
    state beside the cache in another."""
    blender = _blender()
    addon_zip = _addon_zip(tmp_path)
    scripts = tmp_path / "scripts"
    shutil.copytree(Path(plumage.__file__).parent, scripts / "modules" / "plumage", ignore=shutil.ignore_patterns("__pycache__"))
    out = tmp_path / "out"
    out.mkdir()
    script = str(REPO / "blender" / "tests" / "blender_character.py")
    env = {**os.environ, "BLENDER_USER_SCRIPTS": str(scripts), "BLENDER_USER_CONFIG": str(tmp_path / "config")}

    built = _blender_json(blender, ["--python", script, "--", "build", str(addon_zip), str(out)], env)
    assert built["sources"] == ["Crest", "Head", "Torso", "Wing"]  # three skinned meshes and the bone-parented one, once each
    # the flow follows the armature by default: bones' heads plus the two leaf bones' tails, the head the top of B2
    flow = built["flow"]
    assert flow["default"] == "SKELETON" and flow["flow_from"] == "skeleton" and flow["no_source"], flow
    assert flow["joints"] == 5 and flow["head_at"] == [0.0, 0.0, 2.0] and flow["weights_sum_1"], flow
    assert flow["layer_on"] == flow["layer_expected"] > 0, flow
    assert flow["axis"] == ["axis", True, [0, 0, -1]] and flow["front"][:2] == ["front", True] and len(flow["front"][2]) == 3, flow
    limb = built["limb"]
    assert limb["feathers"] >= 15 and limb["p90_deg"] < 10.0, limb  # along the limb's bone
    assert built["torso_down"] > 0.8, (built["torso_down"], limb)  # down the trunk, away from the head
    assert 500 <= built["feathers"] <= 1000 and built["feathers_object_identity"]
    assert all(built["attributes"][k] for k in built["attributes"]), built["attributes"]
    assert built["modal_cancel"]["status"] == ["CANCELLED"] and built["modal_cancel"]["no_run"] and built["modal_cancel"]["no_feathers"], built
    assert built["modal_cancel"]["told"] == ["Dress cancelled: nothing changed"], built
    assert built["modal_finish"]["status"] == ["FINISHED"] and built["modal_finish"]["is_dress"], built
    assert built["job_status"] == "FINISHED" and built["job_is_dress"] and built["job_cancelled"] == "CANCELLED", built
    assert built["attributes"]["material"] == "Plumage feathers"
    frames = built["frames"]
    assert [f["frame_index"] for f in frames] == list(range(20))
    for f in frames:
        assert f["intersecting_pairs"] == 0 and f["body_penetrations"] == 0 and f["mesh_matches"] and f["coverage"] > 0.5, f
    assert built["crest_moved"] > 0.3 and built["crest_rigid_error"] < 1e-5  # it rides the bone rigidly
    assert [s["frame"] for s in built["scrub"]] == [12, 3, 20, 12]
    for s in built["scrub"]:
        assert s["state_is_playback"] and s["mesh_is_playback"] and s["intersecting_pairs"] == 0 and s["body_penetrations"] == 0, s
    assert "save the file first" in built["unsaved_bake_refused"], built["unsaved_bake_refused"]
    assert built["cache_shape"][:1] == [20] and built["cache_shape"][2] == 3 and built["cache_first"] == 1.0
    assert built["cache_is_playback"] and all(built["cache_plays"].values()), built["cache_plays"]
    assert (out / "character.pc2").is_file() and (out / "character.plumage.npz").is_file()

    # a new Blender without the package (empty user scripts): the cache plays from the saved file
    bare = {**os.environ, "BLENDER_USER_SCRIPTS": str(tmp_path / "empty"), "BLENDER_USER_CONFIG": str(tmp_path / "config2")}
    bare.pop("PYTHONPATH", None)
    played = _blender_json(blender, [str(out / "character.blend"), "--python", script, "--", "play", str(out)], bare)
    assert played["modifiers"] == ["MESH_CACHE"]
    assert all(played["matches"].values()), played

    # and with the package: the live system rebuilt from the state beside the cache, resumed at frame 20, then scrubbed
    rebuilt = _blender_json(blender, ["--python", script, "--", "rebuild", str(addon_zip), str(out)], env)
    assert rebuilt["resumed_frame"] == 20 and rebuilt["resumed_is_baked"]
    for c in rebuilt["checks"]:
        assert c["is_baked"] and c["modifier_off"] and c["intersecting_pairs"] == 0 and c["body_penetrations"] == 0, c
    if played["package_importable"]:
        pytest.skip("plumage is importable in Blender's Python from elsewhere: the cache played, but not proven without the package")


def _addon_module(name: str) -> Any:
    """A bpy-free module of the add-on (jobs, pointcache), loaded without Blender."""
    spec = importlib.util.spec_from_file_location(f"plumage_feathers_{name}", REPO / "blender" / "plumage_feathers" / f"{name}.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_dress_job_reports_progress_every_half_second_and_cancels_within_it() -> None:
    """The modal Dress's loop (jobs.drive: what the operator does on each timer
    event and on Esc) with the real library, without Blender: a create of
    about 2 s reports progress at every tick (0.1 s apart, never more than
    0.5 s) and rising; a cancel stops it within 0.5 s with nothing created."""
    jobs = _addon_module("jobs")
    big = uv_sphere(200, 400)

    def make(progress: Any) -> plumage.System:
        return plumage.System(*big, target_feathers=20000, threads=2, seed=3, progress=progress)

    reports: list = []
    job = jobs.DressJob(make)
    status = jobs.drive(job, report=lambda now, fraction: reports.append((now, fraction)))
    assert status == jobs.FINISHED and job.system is not None and job.system.feather_count > 10000
    times = [t for t, _ in reports]
    gaps = np.diff(times)
    assert len(reports) >= 5 and gaps.max() <= 0.5, gaps.max()
    fractions = [f for _, f in reports]
    assert fractions == sorted(fractions) and fractions[-1] == 1.0 and len(set(fractions)) >= 4, fractions
    # the callback stays in the system's configuration: later calls are not stopped by it
    job.cancel()
    job.system.step(big[0])
    job.system.close()

    cancelled_at: list = []

    def esc(now: float) -> bool:
        if not cancelled_at and reports2 and reports2[-1][1] > 0.05:
            cancelled_at.append(now)  # Esc once the create is well under way
        return bool(cancelled_at)

    reports2: list = []
    job = jobs.DressJob(make)
    status = jobs.drive(job, cancel_requested=esc, report=lambda now, fraction: reports2.append((now, fraction)))
    assert status == jobs.CANCELLED and job.system is None and cancelled_at
    assert isinstance(job.error, plumage.PlumageError) and job.error.status_name == "INTERRUPTED", job.error
    latency = reports2[-1][0] - cancelled_at[0]
    assert latency <= 0.5, latency
    print(f"progress ticks {len(reports)}, largest gap {gaps.max():.3f} s; cancel latency {latency:.3f} s")


def test_fake_clock_drives_the_loop_and_pc2_round_trips(tmp_path: Path) -> None:
    """jobs.drive takes its clock, sleep and cancel request from the caller (a
    cancel at the first tick creates nothing); the .pc2 writer and reader agree."""
    jobs, pointcache = _addon_module("jobs"), _addon_module("pointcache")
    verts, tris = uv_sphere()
    ticks = itertools.count()
    job = jobs.DressJob(lambda progress: plumage.System(verts, tris, target_feathers=400, progress=progress))
    seen: list = []
    status = jobs.drive(job, clock=lambda: float(next(ticks)), sleep=lambda s: None, cancel_requested=lambda now: True,
                        report=lambda now, fraction: seen.append(now))
    assert status in (jobs.CANCELLED, jobs.FINISHED)  # FINISHED only if the create ended before its first callback
    assert seen == [float(i) for i in range(len(seen))]
    frames = [np.random.default_rng(k).standard_normal((7, 3)).astype(np.float32) for k in range(4)]
    pointcache.write_pc2(str(tmp_path / "c.pc2"), frames, start_frame=3)
    samples, start, rate = pointcache.read_pc2(str(tmp_path / "c.pc2"))
    assert start == 3.0 and rate == 1.0 and np.array_equal(samples, np.stack(frames))
    assert pointcache.sidecar_path("/x/c.pc2") == "/x/c.plumage.npz"


def test_blender_install_puts_the_package_where_blender_imports_it(tmp_path: Path) -> None:
    """`python -m plumage.blender_install --addon blender/plumage_feathers`
    copies the package into the user modules folder Blender names (here the
    one BLENDER_USER_SCRIPTS points at) and the add-on into its add-ons; a new
    Blender then imports both, the add-on without an import error."""
    blender = _blender()
    scripts = tmp_path / "scripts"
    env = {**os.environ, "BLENDER_USER_SCRIPTS": str(scripts), "BLENDER_USER_CONFIG": str(tmp_path / "config"), "PLUMAGE_BLENDER": blender}
    env.pop("PYTHONPATH", None)
    run = subprocess.run([sys.executable, "-m", "plumage.blender_install", "--addon", str(REPO / "blender" / "plumage_feathers")],
                         stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, env=env, timeout=300)
    assert run.returncode == 0, run.stdout
    assert "Blender imports plumage" in run.stdout, run.stdout
    lib = Path(plumage.library_path()).name
    assert (scripts / "modules" / "plumage" / lib).is_file() and (scripts / "addons" / "plumage_feathers" / "jobs.py").is_file()
    check = ("import bpy, json; bpy.ops.preferences.addon_enable(module='plumage_feathers'); import plumage_feathers as a; "
             "print('PLUMAGE_RESULT ' + json.dumps({'error': a.IMPORT_ERROR, 'file': a.plumage.__file__}))")
    result = _blender_json(blender, ["--python-expr", check], env, factory=False)  # as a user starts it (its config is empty here)
    assert result["error"] == "" and result["file"].startswith(str(scripts / "modules")), result


def test_blender_install_enable_turns_the_addon_on(tmp_path: Path) -> None:
    """`--addon DIR --enable`: the add-on is enabled and the preferences saved, so that a new Blender (as the user
    starts it, its preferences read) has it on, its panel's properties registered, without enabling it by hand."""
    blender = _blender()
    scripts = tmp_path / "scripts"
    env = {**os.environ, "BLENDER_USER_SCRIPTS": str(scripts), "BLENDER_USER_CONFIG": str(tmp_path / "config"), "PLUMAGE_BLENDER": blender}
    env.pop("PYTHONPATH", None)
    run = subprocess.run([sys.executable, "-m", "plumage.blender_install", "--addon", str(REPO / "blender" / "plumage_feathers"), "--enable"],
                         stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, env=env, timeout=300)
    assert run.returncode == 0, run.stdout
    assert "enabled the add-on plumage_feathers" in run.stdout, run.stdout
    check = ("import bpy, json, sys; a = sys.modules.get('plumage_feathers'); "
             "print('PLUMAGE_RESULT ' + json.dumps({'enabled': sorted(x.module for x in bpy.context.preferences.addons), "
             "'loaded': a is not None, 'error': a.IMPORT_ERROR if a else None, 'panel': hasattr(bpy.types.Object, 'plumage')}))")
    result = _blender_json(blender, ["--python-expr", check], env, factory=False)
    assert "plumage_feathers" in result["enabled"] and result["loaded"] and result["error"] == "" and result["panel"], result
    # without --addon, --enable is refused
    run = subprocess.run([sys.executable, "-m", "plumage.blender_install", "--enable"], stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                         text=True, env=env, timeout=60)
    assert run.returncode == 2 and "give --addon DIR too" in run.stdout, run.stdout


def test_type_group_hidden_meshes_panel_figures_and_undo(tmp_path: Path) -> None:
    """A Type group puts scales on one mesh of a rig (width/length of its feathers 1, the rest feathers), 0 pairs
    and 0 penetrations; hidden meshes under the armature are not dressed; the panel's validation figures; an undone
    Dress drops the live system it made (the one it replaced is live again), a redo brings it back."""
    blender = _blender()
    addon_zip = _addon_zip(tmp_path)
    scripts = tmp_path / "scripts"
    shutil.copytree(Path(plumage.__file__).parent, scripts / "modules" / "plumage", ignore=shutil.ignore_patterns("__pycache__"))
    env = {**os.environ, "BLENDER_USER_SCRIPTS": str(scripts), "BLENDER_USER_CONFIG": str(tmp_path / "config")}
    r = _blender_json(blender, ["--python", str(REPO / "blender" / "tests" / "blender_groups.py"), "--", str(addon_zip)], env, timeout=300)
    assert r["sources"] == r["dressed_sources"] == ["Leg", "Torso"], r  # not HiddenViewport nor HiddenLayer
    assert r["types"] == {"dtype": "uint32", "leg_all_scales": True, "torso_all_feathers": True}, r["types"]
    leg, torso = r["leg"], r["torso"]
    assert leg["feathers"] >= 20 and abs(leg["ratio_median"] - 1.0) < 0.05 and 0.9 <= leg["ratio_min"] <= leg["ratio_max"] <= 1.1, leg
    assert torso["feathers"] >= 200 and torso["ratio_median"] < 0.8, torso
    for f in r["frames"]:
        assert f["pairs"] == 0 and f["penetrations"] == 0, f
    assert r["panel_after_dress"][0].startswith("Validated at frame 1: 0 pairs, 0 penetrations"), r["panel_after_dress"]
    assert r["panel_after_validate"][0].startswith("Validated at frame 6: 0 pairs, 0 penetrations"), r["panel_after_validate"]
    assert "coverage" in r["panel_after_validate"][1] and "discord" in r["panel_after_validate"][1]
    figures = r["panel_figures"]
    assert figures["frame"] == 6 and figures["coverage"] > 0.5 and 0 <= figures["discord_percent"] <= 100, figures
    assert r["second_is_other"]
    assert r["undo_restores_first"] and r["restored_mesh_is_current"] and r["restored_follows_frames"], r["undo"]
    assert r["undo_drops_first"] and r["no_stale_follow"], r["undo"]
    assert r["undo_steps_to_first"] == 2, r["undo"]  # the seed's step, then the first Dress's own
    assert not r["undo"][1]["feathers_object"], r["undo"]  # the feathers object the first Dress made is undone too
    assert r["redo_restores_first"], r["undo"]
    assert all(len(u["parked"]) <= r["parked_at_most"] for u in r["undo"]), r["undo"]


@pytest.mark.parametrize("parts", [False, True], ids=["one_mesh", "two_meshes_and_a_rigid_crest"])
def test_imported_gltf_character_is_dressed_valid_and_scrubs_as_playback(tmp_path: Path, parts: bool) -> None:
    """scripts/make_character.py's walking figure through Blender's own glTF importer (with the `numpy.bool = bool`
    shim the README gives for Debian's Blender 3.4 beside numpy 1.24): its armature dressed, 0 pairs and 0
    penetrations on frames 1..8, scrubbing 6, 2, 8 gives playback's state. With `--parts` the figure is two skinned
    meshes on one skin and a crest parented to the head bone: all three are dressed as one coat."""
    blender = _blender()
    addon_zip = _addon_zip(tmp_path)
    model = tmp_path / "character.glb"
    subprocess.run([sys.executable, str(REPO / "scripts" / "make_character.py"), str(model), *(["--parts"] if parts else [])], check=True)
    scripts = tmp_path / "scripts"
    shutil.copytree(Path(plumage.__file__).parent, scripts / "modules" / "plumage", ignore=shutil.ignore_patterns("__pycache__"))
    env = {**os.environ, "BLENDER_USER_SCRIPTS": str(scripts), "BLENDER_USER_CONFIG": str(tmp_path / "config")}
    r = _blender_json(blender, ["--python", str(REPO / "blender" / "tests" / "blender_gltf.py"), "--", str(addon_zip), str(model)], env, timeout=300)
    assert r["sources"] == (["crest", "limbs", "trunk"] if parts else ["body"]) and r["flow_from"] == "skeleton", r
    assert 600 <= r["feathers"] <= 1000 and r["moved"] > 0.05, r
    for f in r["frames"]:
        assert f["pairs"] == 0 and f["penetrations"] == 0 and f["coverage"] > 0.5, f
    assert [s["frame"] for s in r["scrub"]] == [6, 2, 8] and all(s["is_playback"] for s in r["scrub"]), r["scrub"]
