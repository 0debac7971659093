"""Shared fixtures: a small analytic mesh, the repository, the C++ host."""

from __future__ import annotations

import os
import subprocess
from pathlib import Path
from typing import Tuple

import numpy as np
import pytest

REPO = Path(__file__).resolve().parents[2]


def uv_sphere(rings: int = 24, segments: int = 48, radius: float = 1.0) -> Tuple[np.ndarray, np.ndarray]:
    """A closed UV sphere: (vertices float32 (n, 3), triangles int64 (m, 3)), outward-facing."""
    theta = np.linspace(0.0, np.pi, rings)[1:-1]
    phi = np.linspace(0.0, 2 * np.pi, segments, endpoint=False)
    t, p = np.meshgrid(theta, phi, indexing="ij")
    ring = np.stack([np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)], axis=-1).reshape(-1, 3)
    verts = np.concatenate([[[0, 0, 1]], ring, [[0, 0, -1]]]) * radius
    r = len(theta)
    j = np.arange(segments)
    jn = (j + 1) % segments
    tris = [np.stack([np.zeros(segments, int), 1 + j, 1 + jn], axis=1)]
    for i in range(r - 1):
        a, b = 1 + i * segments + j, 1 + i * segments + jn
        tris += [np.stack([a, a + segments, b], axis=1), np.stack([b, a + segments, b + segments], axis=1)]
    last = 1 + r * segments
    tris.append(np.stack([np.full(segments, last), 1 + (r - 1) * segments + jn, 1 + (r - 1) * segments + j], axis=1))
    return verts.astype(np.float32), np.concatenate(tris).astype(np.int64)


def wobble(verts: np.ndarray, k: int) -> np.ndarray:
    """Frame k of a smooth deformation: a travelling bulge and a slow turn."""
    v = verts.astype(np.float64)
    angle = 0.05 * k
    c, s = np.cos(angle), np.sin(angle)
    turned = v @ np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]]).T
    bulge = 1.0 + 0.08 * np.sin(3 * v[:, 2] + 0.6 * k)
    return (turned * bulge[:, None]).astype(np.float32)


@pytest.fixture(scope="session")
def sphere() -> Tuple[np.ndarray, np.ndarray]:
    return uv_sphere()


@pytest.fixture(scope="session")
def host() -> str:
    """The C++ glTF host, built by scripts/test.sh (or $PLUMAGE_GLTF_HOST)."""
    path = os.environ.get("PLUMAGE_GLTF_HOST") or str(REPO / "build" / "plumage_gltf")
    if not (Path(path).is_file() and os.access(path, os.X_OK)):
        pytest.skip(f"the C++ host is not built ({path}): cmake -S cpp_examples -B build && cmake --build build")
    return path


def run_host(host: str, *args: str) -> subprocess.CompletedProcess:
    run = subprocess.run([host, *args], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    assert run.returncode == 0, f"plumage_gltf {' '.join(args)} failed ({run.returncode}): {run.stderr}"
    return run


def glb_node_arrays(path: Path, node_name: str) -> Tuple[np.ndarray, np.ndarray, list]:
    """(positions, triangles as stored, [raw POSITION of each morph target]) of a node of the host's .glb."""
    pygltflib = pytest.importorskip("pygltflib")
    gltf = pygltflib.GLTF2().load(str(path))
    blob = gltf.binary_blob()

    def read(accessor_index: int) -> np.ndarray:
        acc = gltf.accessors[accessor_index]
        view = gltf.bufferViews[acc.bufferView]
        dtype = {5126: np.float32, 5125: np.uint32, 5123: np.uint16}[acc.componentType]
        width = {"SCALAR": 1, "VEC3": 3}[acc.type]
        start = (view.byteOffset or 0) + (acc.byteOffset or 0)
        return np.frombuffer(blob, dtype=dtype, count=acc.count * width, offset=start).reshape(acc.count, width)

    node = next(n for n in gltf.nodes if n.name == node_name)
    prim = gltf.meshes[node.mesh].primitives[0]
    return read(prim.attributes.POSITION), read(prim.indices).reshape(-1, 3), [read(t["POSITION"]) for t in prim.targets or []]


def glb_mesh_frames(path: Path, node_name: str) -> Tuple[np.ndarray, np.ndarray, list]:
    """(base positions, indices, [positions of each morph target applied alone]) of a node of the host's .glb."""
    base, indices, targets = glb_node_arrays(path, node_name)
    return base, indices.astype(np.uint32), [base + t for t in targets]
