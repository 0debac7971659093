"""USD output (needs `usd-core`): the body and the feathers as UsdGeomMesh
prims with time-sampled points and normals, `st` UVs and a per-feather `id`
primvar.

Layout of the stage:

    /Plumage           Xform, the default prim
    /Plumage/Body      the dressed mesh (the rest pose as default value)
    /Plumage/Feathers  every feather as the library lays it out
                       (plumage_system_feather_geometry), in the rest pose's
                       feather order; primvars `st` (vertex: u along the
                       shaft, v across the vanes), `id` (int64, the library's
                       64-bit id reinterpreted as signed, uniform: one per
                       triangle) and `featherIndex` (int, vertex)
    /Plumage/Materials/Body, /Plumage/Materials/Feathers
                       UsdPreviewSurface materials bound to the two meshes
                       (UsdShade.MaterialBindingAPI); each reads the `st`
                       primvar (`inputs:frame:stPrimvarName`) for a texture
                       a user connects. The body has `st` too when the input
                       mesh has UVs (`body_uvs`: per vertex, or per triangle
                       corner as faceVarying).

Time codes are clip seconds × fps, with timeCodesPerSecond = fps.
"""

from __future__ import annotations

from pathlib import Path
from typing import List, Optional, Sequence, Union

import numpy as np
import numpy.typing as npt

from .system import FeatherGeometry, System, vertex_normals

try:
    from pxr import Gf, Sdf, Usd, UsdGeom, UsdShade, Vt  # type: ignore[import-untyped]
except ImportError as e:  # pragma: no cover - exercised only without usd-core
    raise ImportError("plumage.usd needs the usd-core package: pip install usd-core") from e


def _vec3(a: npt.ArrayLike) -> "Vt.Vec3fArray":
    return Vt.Vec3fArray.FromNumpy(np.ascontiguousarray(a, dtype=np.float32).reshape(-1, 3))


def _extent(points: np.ndarray) -> "Vt.Vec3fArray":
    if len(points) == 0:
        return Vt.Vec3fArray([Gf.Vec3f(0, 0, 0), Gf.Vec3f(0, 0, 0)])
    return Vt.Vec3fArray([Gf.Vec3f(*map(float, points.min(axis=0))), Gf.Vec3f(*map(float, points.max(axis=0)))])


def matching_vertices(rest: FeatherGeometry, frame: FeatherGeometry) -> "tuple[np.ndarray, np.ndarray]":
    """(rest vertex rows, frame vertex rows) of the feathers found in both,
    matched by id: how to put a frame's vertices in the rest pose's order."""
    if len(rest.ids) == 0 or len(frame.ids) == 0:
        return np.zeros(0, np.intp), np.zeros(0, np.intp)
    order = np.argsort(rest.ids, kind="stable")
    sorted_ids = rest.ids[order]
    at = np.minimum(np.searchsorted(sorted_ids, frame.ids), len(sorted_ids) - 1)
    found = np.flatnonzero(sorted_ids[at] == frame.ids)
    slots = order[at[found]]
    counts = frame.vertex_counts[found].astype(np.intp)
    if not np.array_equal(counts, rest.vertex_counts[slots]):
        raise ValueError("a feather's vertex count changed from the rest pose")
    rest_first = np.concatenate([[0], np.cumsum(rest.vertex_counts.astype(np.intp))[:-1]])
    frame_first = np.concatenate([[0], np.cumsum(frame.vertex_counts.astype(np.intp))[:-1]])
    within = np.arange(counts.sum()) - np.repeat(np.cumsum(counts) - counts, counts)
    return np.repeat(rest_first[slots], counts) + within, np.repeat(frame_first[found], counts) + within


class UsdWriter:
    """Writes the body and feathers of a run frame by frame."""

    def __init__(
        self,
        path: Union[str, Path],
        fps: float,
        body_rest: np.ndarray,
        body_triangles: np.ndarray,
        feathers_rest: FeatherGeometry,
        up_axis: str = "Y",
        *,
        body_uvs: Optional[npt.ArrayLike] = None,
    ) -> None:
        self.path = str(path)
        self.stage = Usd.Stage.CreateNew(self.path)
        stage = self.stage
        UsdGeom.SetStageUpAxis(stage, UsdGeom.Tokens.y if up_axis.upper() == "Y" else UsdGeom.Tokens.z)
        UsdGeom.SetStageMetersPerUnit(stage, 1.0)
        stage.SetTimeCodesPerSecond(fps)
        stage.SetFramesPerSecond(fps)
        self.fps = fps
        root = UsdGeom.Xform.Define(stage, "/Plumage")
        stage.SetDefaultPrim(root.GetPrim())

        self.body_triangles = np.ascontiguousarray(body_triangles, dtype=np.uint32).reshape(-1, 3)
        self.body = self._mesh("/Plumage/Body", np.asarray(body_rest, np.float32).reshape(-1, 3), self.body_triangles)

        self.rest = feathers_rest
        self.rest_ids = feathers_rest.ids.copy()
        self.feathers = self._mesh("/Plumage/Feathers", feathers_rest.positions, feathers_rest.triangles, feathers_rest.normals)
        self.feathers.GetDoubleSidedAttr().Set(True)
        pv = UsdGeom.PrimvarsAPI(self.feathers.GetPrim())
        per_triangle_feather = np.repeat(np.arange(len(self.rest_ids)), feathers_rest.triangle_counts.astype(np.intp))
        ids = pv.CreatePrimvar("id", Sdf.ValueTypeNames.Int64Array, UsdGeom.Tokens.uniform)
        ids.Set(Vt.Int64Array.FromNumpy(self.rest_ids.view(np.int64)[per_triangle_feather]))
        index = pv.CreatePrimvar("featherIndex", Sdf.ValueTypeNames.IntArray, UsdGeom.Tokens.vertex)
        index.Set(Vt.IntArray.FromNumpy(feathers_rest.feather_index.astype(np.int32)))
        st = pv.CreatePrimvar("st", Sdf.ValueTypeNames.TexCoord2fArray, UsdGeom.Tokens.vertex)
        st.Set(Vt.Vec2fArray.FromNumpy(np.ascontiguousarray(feathers_rest.uvs, dtype=np.float32)))
        self._feather_points = feathers_rest.positions
        self._feather_normals = feathers_rest.normals
        self.time_codes: List[float] = []
        if body_uvs is not None:
            self._body_st(np.asarray(body_uvs, dtype=np.float32))
        self._bind(self.body, "Body", (0.8, 0.62, 0.5), 0.7)
        self._bind(self.feathers, "Feathers", (0.45, 0.3, 0.18), 0.55)

    def _body_st(self, uvs: np.ndarray) -> None:
        """`primvars:st` of the body: one UV per vertex, or one per triangle corner."""
        n, m = len(self.body.GetPointsAttr().Get()), len(self.body_triangles)
        if uvs.ndim == 1 and uvs.size % 2 == 0:
            uvs = uvs.reshape(-1, 2)
        uvs = np.ascontiguousarray(uvs, dtype=np.float32)
        if uvs.ndim != 2 or uvs.shape[1] != 2 or len(uvs) not in (n, 3 * m):
            raise ValueError(f"body_uvs: expected ({n}, 2) per vertex or ({3 * m}, 2) per triangle corner, got {uvs.shape}")
        interpolation = UsdGeom.Tokens.vertex if len(uvs) == n else UsdGeom.Tokens.faceVarying
        st = UsdGeom.PrimvarsAPI(self.body.GetPrim()).CreatePrimvar("st", Sdf.ValueTypeNames.TexCoord2fArray, interpolation)
        st.Set(Vt.Vec2fArray.FromNumpy(uvs))

    def _bind(self, mesh: "UsdGeom.Mesh", name: str, colour: "tuple[float, float, float]", roughness: float) -> None:
        """A UsdPreviewSurface material at /Plumage/Materials/NAME bound to `mesh`."""
        material = UsdShade.Material.Define(self.stage, f"/Plumage/Materials/{name}")
        material.CreateInput("frame:stPrimvarName", Sdf.ValueTypeNames.Token).Set("st")
        shader = UsdShade.Shader.Define(self.stage, f"/Plumage/Materials/{name}/PreviewSurface")
        shader.CreateIdAttr("UsdPreviewSurface")
        shader.CreateInput("diffuseColor", Sdf.ValueTypeNames.Color3f).Set(Gf.Vec3f(*colour))
        shader.CreateInput("roughness", Sdf.ValueTypeNames.Float).Set(roughness)
        material.CreateSurfaceOutput().ConnectToSource(shader.ConnectableAPI(), "surface")
        UsdShade.MaterialBindingAPI.Apply(mesh.GetPrim()).Bind(material)

    def _mesh(self, path: str, points: np.ndarray, triangles: np.ndarray, normals: Optional[np.ndarray] = None) -> "UsdGeom.Mesh":
        mesh = UsdGeom.Mesh.Define(self.stage, path)
        mesh.CreateSubdivisionSchemeAttr(UsdGeom.Tokens.none)
        mesh.CreateFaceVertexCountsAttr(Vt.IntArray.FromNumpy(np.full(len(triangles), 3, dtype=np.int32)))
        mesh.CreateFaceVertexIndicesAttr(Vt.IntArray.FromNumpy(np.ascontiguousarray(triangles, dtype=np.int32).reshape(-1)))
        mesh.CreatePointsAttr(_vec3(points))
        mesh.CreateExtentAttr(_extent(points))
        mesh.CreateNormalsAttr(_vec3(vertex_normals(points, triangles) if normals is None else normals))
        mesh.SetNormalsInterpolation(UsdGeom.Tokens.vertex)
        return mesh

    def add_frame(self, seconds: float, body_points: np.ndarray, feathers: FeatherGeometry) -> None:
        tc = Usd.TimeCode(seconds * self.fps)
        self.time_codes.append(tc.GetValue())
        body = np.asarray(body_points, np.float32).reshape(-1, 3)
        self.body.GetPointsAttr().Set(_vec3(body), tc)
        self.body.GetNormalsAttr().Set(_vec3(vertex_normals(body, self.body_triangles)), tc)
        self.body.GetExtentAttr().Set(_extent(body), tc)
        if np.array_equal(feathers.ids, self.rest_ids) and np.array_equal(feathers.vertex_counts, self.rest.vertex_counts):
            points, normals = feathers.positions, feathers.normals  # the usual case: the layout never changes
        else:
            # a feather absent from this frame keeps its previous pose (as the
            # C++ host's .glb does); one absent at rest is left out
            dest, src = matching_vertices(self.rest, feathers)
            points, normals = self._feather_points.copy(), self._feather_normals.copy()
            points[dest], normals[dest] = feathers.positions[src], feathers.normals[src]
        self._feather_points, self._feather_normals = points, normals
        self.feathers.GetPointsAttr().Set(_vec3(points), tc)
        self.feathers.GetNormalsAttr().Set(_vec3(normals), tc)
        self.feathers.GetExtentAttr().Set(_extent(self._feather_points), tc)

    def save(self) -> None:
        if self.time_codes:
            self.stage.SetStartTimeCode(min(self.time_codes))
            self.stage.SetEndTimeCode(max(self.time_codes))
        self.stage.GetRootLayer().Save()


def write_run(
    path: Union[str, Path],
    system: System,
    rest: np.ndarray,
    triangles: np.ndarray,
    frames: Union[Sequence[np.ndarray], np.ndarray],
    times: Union[Sequence[float], np.ndarray],
    fps: float,
    *,
    body_uvs: Optional[npt.ArrayLike] = None,
) -> None:
    """Steps `system` through `frames` (at clip `times`) and writes the run
    (`body_uvs`: the input mesh's UVs, per vertex or per triangle corner)."""
    writer = UsdWriter(path, fps, rest, triangles, system.feather_geometry(), body_uvs=body_uvs)
    for seconds, frame in zip(times, frames):
        system.step(frame)
        writer.add_frame(float(seconds), frame, system.feather_geometry())
    writer.save()
