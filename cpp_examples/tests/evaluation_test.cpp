// glTF evaluation checked against analytic answers, on small files each
// case writes itself: skins, morph targets, samplers, sparse accessors,
// hierarchies, strides, primitives, file formats and refusals.
//   evaluation_test CASE WORK_DIR
#include "errors.h"
#include "check.h"
#include "gltf_fixture.h"
#include "gltf_loader.h"
#include "gltf_scene.h"
#include "procedural_model.h"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <map>
#include <string>

using plumage_host::GltfScene;
using plumage_host::InputError;
using plumage_host::UsageError;
using namespace plumage_test;
using json = nlohmann::json;

namespace {

using plumage_check::check;

std::string g_dir;

std::string path(const std::string& name) { return (std::filesystem::path(g_dir) / name).string(); }

GltfScene open(const GltfFixture& f, const std::string& name, const std::string& mesh = "", const std::string& clip = "",
               GltfFormat format = GltfFormat::Glb) {
    f.write(path(name), format);
    return GltfScene(plumage_host::load_gltf_file(path(name)), mesh, clip);
}

std::vector<float> pose(const GltfScene& s, double t) {
    std::vector<float> xyz;
    s.pose_at(t, xyz);
    return xyz;
}

void expect_vertex(const std::vector<float>& xyz, size_t v, double x, double y, double z, int line, double tol = 1e-5) {
    const bool inside = 3 * v + 2 < xyz.size();
    const double px = inside ? xyz[3 * v] : NAN, py = inside ? xyz[3 * v + 1] : NAN, pz = inside ? xyz[3 * v + 2] : NAN;
    const bool ok = std::fabs(px - x) <= tol && std::fabs(py - y) <= tol && std::fabs(pz - z) <= tol;
    char what[200];
    std::snprintf(what, sizeof what, "vertex %zu is (%.6f, %.6f, %.6f), expected (%.6f, %.6f, %.6f)", v, px, py, pz, x, y, z);
    check(ok, what, line);
}
#define EXPECT_VERTEX(xyz, v, x, y, z) expect_vertex((xyz), (v), (x), (y), (z), __LINE__)

template <class E, class F>
void expect_throw(F&& f, const std::string& needle, int line) {
    try {
        f();
        check(false, "expected an exception mentioning \"" + needle + "\"", line);
    } catch (const E& e) {
        check(std::string(e.what()).find(needle) != std::string::npos, std::string("message \"") + e.what() + "\" mentions \"" + needle + "\"", line);
    }
}
#define EXPECT_THROW(E, expr, needle) expect_throw<E>([&] { (void)(expr); }, (needle), __LINE__)

constexpr double kS = 0.70710678118654752;  // sin 45° = cos 45°

// One triangle (0,0,0), (1,0,0), (0,1,0) as mesh 0.
int triangle_mesh(GltfFixture& f) {
    const int pos = f.floats({0, 0, 0, 1, 0, 0, 0, 1, 0}, "VEC3");
    return f.add("meshes", {{"primitives", {{{"attributes", {{"POSITION", pos}}}}}}});
}

// An animation of one channel on node 0.
void animate(GltfFixture& f, const std::string& path, const std::vector<float>& times, const std::vector<float>& values, const std::string& type,
             const std::string& interpolation) {
    const int in = f.floats(times, "SCALAR");
    const int out = f.floats(values, type);
    f.add("animations", {{"name", path + "_" + interpolation},
                         {"samplers", {{{"input", in}, {"output", out}, {"interpolation", interpolation}}}},
                         {"channels", {{{"sampler", 0}, {"target", {{"node", 0}, {"path", path}}}}}}});
}

// ---- skins --------------------------------------------------------------

// Two joints under an armature at (0,0,5); the child joint sits at y = 1 and
// turns 90° about z between t = 0 and 1. The skinned node's own
// translation (10,0,0) must be ignored.
GltfFixture two_bone_skin(bool u8_joints, bool with_ibm, const std::vector<float>& positions) {
    GltfFixture f;
    const int pos = f.floats(positions, "VEC3");
    const int idx = f.u16({0, 1, 3, 1, 2, 3}, "SCALAR");
    int joints, weights;
    if (u8_joints) {
        joints = f.u8({0, 0, 0, 0, 0, 1, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0}, "VEC4");
        weights = f.u8({255, 0, 0, 0, 128, 127, 0, 0, 255, 0, 0, 0, 255, 0, 0, 0}, "VEC4", true);
    } else {
        joints = f.u16({0, 0, 0, 0, 0, 1, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0}, "VEC4");
        weights = f.floats({1, 0, 0, 0, 0.5f, 0.5f, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0}, "VEC4");
    }
    f.add("meshes", {{"primitives", {{{"attributes", {{"POSITION", pos}, {"JOINTS_0", joints}, {"WEIGHTS_0", weights}}}, {"indices", idx}}}}});
    f.add("nodes", {{"name", "armature"}, {"translation", {0, 0, 5}}, {"children", {1, 3}}});
    f.add("nodes", {{"name", "root"}, {"children", {2}}});
    f.add("nodes", {{"name", "child"}, {"translation", {0, 1, 0}}});
    f.add("nodes", {{"name", "skinned"}, {"mesh", 0}, {"skin", 0}, {"translation", {10, 0, 0}}});
    json skin = {{"joints", {1, 2}}};
    if (with_ibm) {
        // Inverse bind matrices: the inverses of the joints' rest globals, T(0,0,-5) and T(0,-1,-5).
        skin["inverseBindMatrices"] = f.floats({1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, -5, 1, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, -1, -5, 1}, "MAT4");
    }
    f.add("skins", skin);
    f.doc()["scenes"] = json::array({{{"nodes", {0}}}});
    const int in = f.floats({0, 1}, "SCALAR");
    const int out = f.floats({0, 0, 0, 1, 0, 0, static_cast<float>(kS), static_cast<float>(kS)}, "VEC4");
    f.add("animations", {{"name", "bend"},
                         {"samplers", {{{"input", in}, {"output", out}}}},
                         {"channels", {{{"sampler", 0}, {"target", {{"node", 2}, {"path", "rotation"}}}}}}});
    return f;
}

void skin_u8_normalized_with_ibm() {
    // Mesh positions are the rest pose; the IBMs bring them into joint space.
    const GltfScene s = open(two_bone_skin(true, true, {0, 0, 5, 0, 1, 5, 0, 2, 5, 0.5f, 2, 5}), "skin_u8.glb");
    CHECK(s.skinned());
    const std::vector<float> rest = s.rest_positions();
    EXPECT_VERTEX(rest, 0, 0, 0, 5);
    EXPECT_VERTEX(rest, 2, 0, 2, 5);
    const std::vector<float> end = pose(s, 1.0);
    EXPECT_VERTEX(end, 0, 0, 0, 5);
    EXPECT_VERTEX(end, 1, 0, 1, 5);  // half on each joint, both map it to the elbow
    EXPECT_VERTEX(end, 2, -1, 1, 5);
    EXPECT_VERTEX(end, 3, -1, 1.5, 5);
    const std::vector<float> mid = pose(s, 0.5);  // slerp: 45°
    EXPECT_VERTEX(mid, 2, -kS, 1 + kS, 5);
}

void skin_u16_float_without_ibm() {
    // No IBMs: identity, so mesh positions are already in each joint's space.
    const GltfScene s = open(two_bone_skin(false, false, {0, 0, 0, 0, 0, 0, 0, 1, 0, 0.5f, 1, 0}), "skin_u16.gltf", "", "", GltfFormat::Embedded);
    const std::vector<float> rest = s.rest_positions();
    EXPECT_VERTEX(rest, 0, 0, 0, 5);
    EXPECT_VERTEX(rest, 1, 0, 0.5, 5);  // halfway between the joints' origins
    EXPECT_VERTEX(rest, 2, 0, 2, 5);
    const std::vector<float> end = pose(s, 1.0);
    EXPECT_VERTEX(end, 2, -1, 1, 5);
    EXPECT_VERTEX(end, 3, -1, 1.5, 5);
    EXPECT_VERTEX(end, 1, 0, 0.5, 5);
}

// ---- morph targets ------------------------------------------------------

// A unit cube (8 vertices, 12 triangles) with three targets: 0 dense (the
// x = 1 face moves +1 in x), 1 an accessor without a buffer view (all
// zeros), 2 sparse on zeros (vertex 7 moves +2 in z).
GltfFixture morph_cube() {
    GltfFixture f;
    std::vector<float> p, d0;
    for (int i = 0; i < 8; ++i) {
        const float x = static_cast<float>(i & 1), y = static_cast<float>((i >> 1) & 1), z = static_cast<float>((i >> 2) & 1);
        p.insert(p.end(), {x, y, z});
        d0.insert(d0.end(), {x, 0, 0});
    }
    const int pos = f.floats(p, "VEC3");
    const int idx = f.u8({0, 2, 1, 1, 2, 3, 4, 5, 6, 5, 7, 6, 0, 1, 4, 1, 5, 4, 2, 6, 3, 3, 6, 7, 0, 4, 2, 2, 4, 6, 1, 3, 5, 3, 7, 5}, "SCALAR");
    const int t0 = f.floats(d0, "VEC3");
    const int t1 = f.accessor(-1, kFloat, 8, "VEC3");
    f.bounds(t1, {0, 0, 0}, 3);
    const int t2 = f.accessor(-1, kFloat, 8, "VEC3");
    f.bounds(t2, {0, 0, 0, 0, 0, 2}, 3);
    f.doc()["accessors"][t2]["sparse"] = {{"count", 1},
                                          {"indices", {{"bufferView", f.view(std::vector<uint8_t>{7, 0, 0, 0})}, {"componentType", kUByte}}},
                                          {"values", {{"bufferView", f.view(std::vector<float>{0, 0, 2})}}}};
    f.add("meshes", {{"primitives", {{{"attributes", {{"POSITION", pos}}},
                                      {"indices", idx},
                                      {"targets", {{{"POSITION", t0}}, {{"POSITION", t1}}, {{"POSITION", t2}}}}}}},
                     {"weights", {0.25, 0, 0}}});
    f.add("nodes", {{"mesh", 0}, {"translation", {0, 3, 0}}});
    f.doc()["scenes"] = json::array({{{"nodes", {0}}}});
    return f;
}

void morph_cube_animated() {
    GltfFixture f = morph_cube();
    animate(f, "weights", {0, 1}, {0, 0, 0, 1, 1, 0.5f}, "SCALAR", "LINEAR");
    const GltfScene s = open(f, "morph_cube.glb");
    CHECK(s.morph_target_count() == 3);
    const std::vector<float> rest = s.rest_positions();  // mesh weights [0.25, 0, 0]
    EXPECT_VERTEX(rest, 1, 1.25, 3, 0);
    EXPECT_VERTEX(rest, 7, 1.25, 4, 1);
    EXPECT_VERTEX(rest, 0, 0, 3, 0);
    const std::vector<float> mid = pose(s, 0.5);  // weights [0.5, 0.5, 0.25]
    EXPECT_VERTEX(mid, 1, 1.5, 3, 0);
    EXPECT_VERTEX(mid, 7, 1.5, 4, 1.5);
    EXPECT_VERTEX(mid, 6, 0, 4, 1);
    const std::vector<float> end = pose(s, 1.0);
    EXPECT_VERTEX(end, 7, 2, 4, 2);
}

void morph_weight_precedence() {
    // Animation weights, else the node's, else the mesh's.
    GltfFixture f = morph_cube();
    f.doc()["meshes"][0]["weights"] = {0, 0, 1};
    f.doc()["nodes"][0]["weights"] = {1, 0, 0};
    const GltfScene s = open(f, "morph_precedence.glb");
    CHECK(!s.clip());
    EXPECT_VERTEX(s.rest_positions(), 7, 2, 4, 1);  // node weights: target 0 only
    EXPECT_VERTEX(pose(s, 3.0), 7, 2, 4, 1);
    f.doc()["nodes"][0].erase("weights");
    const GltfScene m = open(f, "morph_precedence_mesh.glb");
    EXPECT_VERTEX(m.rest_positions(), 7, 1, 4, 3);  // mesh weights: target 2 only
}

void morph_cubicspline_weights() {
    // CUBICSPLINE weights: per key, in-tangents, values, out-tangents (3 targets each).
    GltfFixture f = morph_cube();
    animate(f, "weights", {0, 2}, {0, 0, 0, 0, 0, 0, 1, 0, 0, /**/ 0, 0, 0, 1, 0, 0, 0, 0, 0}, "SCALAR", "CUBICSPLINE");
    const GltfScene s = open(f, "morph_cubic.glb");
    // Target 0 weight: value 0 -> 1 with out-tangent 1/s, in-tangent 0; s = 0.25 gives 0.4375.
    EXPECT_VERTEX(pose(s, 0.5), 1, 1.4375, 3, 0);
}

// ---- samplers -----------------------------------------------------------

double translated_x(const GltfScene& s, double t) { return pose(s, t)[0]; }

void sampler_step() {
    GltfFixture f;
    f.single_node_scene(triangle_mesh(f));
    animate(f, "translation", {0, 1, 2}, {0, 0, 0, 5, 0, 0, 10, 0, 0}, "VEC3", "STEP");
    const GltfScene s = open(f, "step.glb");
    CHECK(translated_x(s, -1) == 0);
    CHECK(translated_x(s, 0.99) == 0);
    CHECK(translated_x(s, 1.0) == 5);
    CHECK(translated_x(s, 1.5) == 5);
    CHECK(translated_x(s, 2.5) == 10);
    CHECK(s.clip() && s.clip()->duration == 2.0);
}

void sampler_linear() {
    GltfFixture f;
    f.single_node_scene(triangle_mesh(f));
    animate(f, "translation", {0, 1, 2}, {0, 0, 0, 5, 0, 0, 10, 0, 0}, "VEC3", "LINEAR");
    const GltfScene s = open(f, "linear.glb");
    CHECK(std::fabs(translated_x(s, 0.25) - 1.25) < 1e-6);
    CHECK(std::fabs(translated_x(s, 1.5) - 7.5) < 1e-6);
    CHECK(translated_x(s, 5) == 10);
}

void sampler_cubicspline() {
    GltfFixture f;
    f.single_node_scene(triangle_mesh(f));
    // Keys at t = 0 and 2; x: value 0 -> 1, out-tangent 1/s at the first key, in-tangent 0 at the second.
    animate(f, "translation", {0, 2}, {0, 0, 0, 0, 0, 0, 1, 0, 0, /**/ 0, 0, 0, 1, 0, 0, 0, 0, 0}, "VEC3", "CUBICSPLINE");
    const GltfScene s = open(f, "cubic.glb");
    CHECK(std::fabs(translated_x(s, 0.5) - 0.4375) < 1e-6);  // s = 0.25: h01 + td * h10 = 0.15625 + 2 * 0.140625
    CHECK(std::fabs(translated_x(s, 1.0) - 0.75) < 1e-6);
    CHECK(std::fabs(translated_x(s, 2.0) - 1.0) < 1e-6);
}

void rotation_shortest_path() {
    // The second key is -q(90° about z): the same rotation, so halfway is 45°, not the long way round.
    GltfFixture f;
    f.single_node_scene(triangle_mesh(f));
    animate(f, "rotation", {0, 1}, {0, 0, 0, 1, 0, 0, -static_cast<float>(kS), -static_cast<float>(kS)}, "VEC4", "LINEAR");
    const GltfScene s = open(f, "slerp.glb");
    EXPECT_VERTEX(pose(s, 0.5), 1, kS, kS, 0);
    EXPECT_VERTEX(pose(s, 1.0), 1, 0, 1, 0);
}

void rotation_cubicspline() {
    // Zero tangents: halfway is the normalized mean of the two keys, 45°.
    GltfFixture f;
    f.single_node_scene(triangle_mesh(f));
    const float s = static_cast<float>(kS);
    animate(f, "rotation", {0, 1}, {0, 0, 0, 0, 0, 0, 0, 1, 0, 0, 0, 0, /**/ 0, 0, 0, 0, 0, 0, s, s, 0, 0, 0, 0}, "VEC4", "CUBICSPLINE");
    const GltfScene scene = open(f, "slerp_cubic.glb");
    EXPECT_VERTEX(pose(scene, 0.5), 1, kS, kS, 0);
}

// ---- accessors ----------------------------------------------------------

void sparse_positions() {
    // Dense base, then vertices 1 and 2 replaced (u8 indices, then u16 with byte offsets).
    for (const int index_type : {kUByte, kUShort}) {
        GltfFixture f;
        const int pos = f.floats({0, 0, 0, 1, 0, 0, 0, 1, 0}, "VEC3");
        const int ind = index_type == kUByte ? f.view(std::vector<uint8_t>{1, 2, 0, 0}) : f.view(std::vector<uint16_t>{99, 1, 2, 0});
        const int val = f.view(std::vector<float>{-1, -1, -1, 4, 0, 0, 0, 4, 0});
        f.doc()["accessors"][pos]["sparse"] = {{"count", 2},
                                               {"indices", {{"bufferView", ind}, {"componentType", index_type}, {"byteOffset", index_type == kUByte ? 0 : 2}}},
                                               {"values", {{"bufferView", val}, {"byteOffset", 12}}}};
        f.bounds(pos, {0, 0, 0, 4, 0, 0, 0, 4, 0}, 3);
        f.add("meshes", {{"primitives", {{{"attributes", {{"POSITION", pos}}}}}}});
        f.single_node_scene(0);
        const GltfScene s = open(f, "sparse.glb");
        EXPECT_VERTEX(s.rest_positions(), 0, 0, 0, 0);
        EXPECT_VERTEX(s.rest_positions(), 1, 4, 0, 0);
        EXPECT_VERTEX(s.rest_positions(), 2, 0, 4, 0);
    }
}

void byte_stride() {
    // POSITION interleaved with another VEC3 (stride 24); a morph target with stride 16.
    GltfFixture f;
    const std::vector<float> interleaved{0, 0, 0, 9, 9, 9, 1, 0, 0, 9, 9, 9, 0, 1, 0, 9, 9, 9};
    const int v = f.view(interleaved, 24);
    const int pos = f.accessor(v, kFloat, 3, "VEC3");
    const int normal = f.accessor(v, kFloat, 3, "VEC3", 12);
    const int tv = f.view(std::vector<float>{0, 0, 1, 7, 0, 0, 2, 7, 0, 0, 3, 7}, 16);
    const int target = f.accessor(tv, kFloat, 3, "VEC3");
    f.bounds(pos, {0, 0, 0, 1, 1, 0}, 3);
    f.bounds(target, {0, 0, 1, 0, 0, 3}, 3);
    f.add("meshes", {{"primitives", {{{"attributes", {{"POSITION", pos}, {"NORMAL", normal}}}, {"targets", {{{"POSITION", target}}}}}}}, {"weights", {1}}});
    f.single_node_scene(0);
    const GltfScene s = open(f, "stride.gltf", "", "", GltfFormat::External);
    EXPECT_VERTEX(s.rest_positions(), 0, 0, 0, 1);
    EXPECT_VERTEX(s.rest_positions(), 1, 1, 0, 2);
    EXPECT_VERTEX(s.rest_positions(), 2, 0, 1, 3);
}

void quantized_positions() {
    // KHR_mesh_quantization: normalized shorts (32767 -> 1), scaled back by the node.
    GltfFixture f;
    const int pos = f.accessor(f.view(std::vector<int16_t>{0, 0, 0, 0, 32767, 0, 0, 0, 0, 32767, 0, 0}, 8), kShort, 3, "VEC3", 0, true);
    f.doc()["accessors"][pos]["min"] = {0, 0, 0};
    f.doc()["accessors"][pos]["max"] = {32767, 32767, 0};
    f.add("meshes", {{"primitives", {{{"attributes", {{"POSITION", pos}}}}}}});
    f.single_node_scene(0);
    f.doc()["nodes"][0]["scale"] = {2, 2, 2};
    f.doc()["extensionsUsed"] = {"KHR_mesh_quantization"};
    f.doc()["extensionsRequired"] = {"KHR_mesh_quantization"};
    const GltfScene s = open(f, "quantized.glb");
    EXPECT_VERTEX(s.rest_positions(), 1, 2, 0, 0);
    EXPECT_VERTEX(s.rest_positions(), 2, 0, 2, 0);
}

// ---- scene structure ----------------------------------------------------

void hierarchy_matrix_and_trs() {
    // Parent: a column-major matrix T(1,2,3) * Ry(90°). Child: TRS t(1,0,0), Rz(90°), s = 2.
    GltfFixture f;
    const int mesh = triangle_mesh(f);
    f.add("nodes", {{"matrix", {0, 0, -1, 0, 0, 1, 0, 0, 1, 0, 0, 0, 1, 2, 3, 1}}, {"children", {1}}});
    f.add("nodes", {{"mesh", mesh}, {"translation", {1, 0, 0}}, {"rotation", {0, 0, kS, kS}}, {"scale", {2, 2, 2}}});
    f.doc()["scenes"] = json::array({{{"nodes", {0}}}});
    const GltfScene s = open(f, "hierarchy.glb");
    // (1,0,0): scale (2,0,0), Rz (0,2,0), +t (1,2,0); Ry (0,2,-1); +T (1,4,2).
    EXPECT_VERTEX(s.rest_positions(), 1, 1, 4, 2);
    EXPECT_VERTEX(s.rest_positions(), 0, 1, 2, 2);
}

void several_primitives() {
    // u8-indexed list, unindexed list, u16 strip and a POINTS primitive (skipped), concatenated.
    GltfFixture f;
    const int p0 = f.floats({0, 0, 0, 1, 0, 0, 0, 1, 0}, "VEC3");
    const int i0 = f.u8({0, 1, 2}, "SCALAR");
    const int p1 = f.floats({5, 0, 0, 6, 0, 0, 5, 1, 0}, "VEC3");
    const int p2 = f.floats({0, 0, 9, 1, 0, 9, 0, 1, 9, 1, 1, 9}, "VEC3");
    const int i2 = f.u16({0, 1, 2, 3}, "SCALAR");
    f.add("meshes", {{"primitives",
                      {{{"attributes", {{"POSITION", p0}}}, {"indices", i0}},
                       {{"attributes", {{"POSITION", p1}}}},
                       {{"attributes", {{"POSITION", p2}}}, {"indices", i2}, {"mode", 5}},
                       {{"attributes", {{"POSITION", p0}}}, {"mode", 0}}}}});
    f.single_node_scene(0);
    const GltfScene s = open(f, "primitives.glb");
    CHECK(s.vertex_count() == 10);
    const std::vector<uint32_t> expected{0, 1, 2, 3, 4, 5, 6, 7, 8, 8, 7, 9};  // the strip's second triangle keeps its winding
    CHECK(s.triangles() == expected);
    EXPECT_VERTEX(s.rest_positions(), 9, 1, 1, 9);
}

void file_formats() {
    // The same animated skin as .glb, .gltf with a data URI and .gltf with a .bin.
    const GltfFixture f = two_bone_skin(true, true, {0, 0, 5, 0, 1, 5, 0, 2, 5, 0.5f, 2, 5});
    const std::vector<float> glb = pose(open(f, "formats.glb"), 0.7);
    CHECK(pose(open(f, "formats_embedded.gltf", "", "", GltfFormat::Embedded), 0.7) == glb);
    CHECK(pose(open(f, "formats_external.gltf", "", "", GltfFormat::External), 0.7) == glb);
}

void default_mesh_and_clip() {
    // A big static mesh and a smaller morphed one: the morphed one is dressed by default.
    GltfFixture f = morph_cube();
    std::vector<float> grid;
    for (int i = 0; i < 60; ++i) grid.insert(grid.end(), {static_cast<float>(i), 0, 0, static_cast<float>(i), 1, 0, static_cast<float>(i) + 1, 0, 0});
    f.doc()["meshes"][0]["name"] = "cube";
    f.add("meshes", {{"name", "ground"}, {"primitives", {{{"attributes", {{"POSITION", f.floats(grid, "VEC3")}}}}}}});
    f.add("nodes", {{"mesh", 1}});
    f.doc()["scenes"][0]["nodes"].push_back(1);
    animate(f, "weights", {0, 1}, {0, 0, 0, 1, 0, 0}, "SCALAR", "LINEAR");
    animate(f, "weights", {0.5f, 3}, {0, 0, 0, 0, 0, 1}, "SCALAR", "STEP");
    f.doc()["animations"][1]["name"] = "second";
    const GltfScene s = open(f, "choice.glb");
    CHECK(s.mesh_name() == "cube");
    CHECK(s.clip() && s.clip()->index == 0);
    CHECK(open(f, "choice.glb", "ground").mesh_name() == "ground");
    CHECK(open(f, "choice.glb", "1").mesh_name() == "ground");
    const GltfScene second = open(f, "choice.glb", "", "second");
    CHECK(second.clip() && second.clip()->index == 1 && second.clip()->start == 0.5 && second.clip()->duration == 2.5);
    CHECK(open(f, "choice.glb", "", "1").clip()->name == "second");
    EXPECT_THROW(UsageError, open(f, "choice.glb", "nope"), "no such mesh");
    EXPECT_THROW(UsageError, open(f, "choice.glb", "", "7"), "no such clip");
}

// ---- refusals -----------------------------------------------------------

void refusals() {
    GltfFixture f;
    f.single_node_scene(triangle_mesh(f));
    f.doc()["extensionsRequired"] = {"KHR_draco_mesh_compression"};
    EXPECT_THROW(InputError, open(f, "draco.glb"), "KHR_draco_mesh_compression");
    f.doc()["extensionsRequired"] = {"EXT_meshopt_compression"};
    EXPECT_THROW(InputError, open(f, "meshopt.glb"), "EXT_meshopt_compression");
    f.doc()["extensionsRequired"] = {"KHR_materials_pbrSpecularGlossiness", "KHR_texture_transform"};  // nothing the host reads
    CHECK(open(f, "materials.glb").vertex_count() == 3);

    GltfFixture past;
    const int pos = past.floats({0, 0, 0, 1, 0, 0, 0, 1, 0}, "VEC3");
    past.doc()["accessors"][pos]["count"] = 4;  // one element more than the view holds
    past.add("meshes", {{"primitives", {{{"attributes", {{"POSITION", pos}}}}}}});
    past.single_node_scene(0);
    EXPECT_THROW(InputError, open(past, "past_end.glb"), "past the end");

    GltfFixture bad_index;
    const int p = bad_index.floats({0, 0, 0, 1, 0, 0, 0, 1, 0}, "VEC3");
    bad_index.add("meshes", {{"primitives", {{{"attributes", {{"POSITION", p}}}, {"indices", bad_index.u8({0, 1, 3}, "SCALAR")}}}}});
    bad_index.single_node_scene(0);
    EXPECT_THROW(InputError, open(bad_index, "bad_index.glb"), "past the vertex count");

    GltfFixture cycle;
    cycle.add("meshes", {{"primitives", {{{"attributes", {{"POSITION", cycle.floats({0, 0, 0, 1, 0, 0, 0, 1, 0}, "VEC3")}}}}}}});
    cycle.add("nodes", {{"mesh", 0}, {"children", {1}}});
    cycle.add("nodes", {{"children", {0}}});
    EXPECT_THROW(InputError, open(cycle, "cycle.glb"), "cycle");

    GltfFixture unknown;
    unknown.single_node_scene(triangle_mesh(unknown));
    animate(unknown, "translation", {0, 1}, {0, 0, 0, 1, 1, 1}, "VEC3", "BEZIER");
    EXPECT_THROW(InputError, open(unknown, "bezier.glb"), "BEZIER");

    GltfFixture nothing;
    nothing.add("nodes", json::object());
    EXPECT_THROW(InputError, open(nothing, "empty.gltf", "", "", GltfFormat::Embedded), "no triangle mesh");
}

// ---- the built-in model -------------------------------------------------

// Closed and wound outward: the signed volume is positive.
double signed_volume(const plumage_host::ProceduralBody& body) {
    double volume = 0;
    const std::vector<float>& p = body.rest_positions();
    const std::vector<uint32_t>& t = body.triangles();
    for (size_t i = 0; i < t.size(); i += 3) {
        const float* a = &p[3 * t[i]];
        const float* b = &p[3 * t[i + 1]];
        const float* c = &p[3 * t[i + 2]];
        volume += (a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) + a[2] * (b[0] * c[1] - b[1] * c[0])) / 6.0;
    }
    return volume;
}

void procedural_body() {
    const plumage_host::ProceduralBody body;
    CHECK(body.triangle_count() == 6016);
    std::vector<float> start, later;
    body.pose_at(0, start);
    body.pose_at(1.0, later);
    CHECK(start == body.rest_positions());
    CHECK(later.size() == start.size() && later != start);
    CHECK(signed_volume(body) > 0.5);
    // Other resolutions (--model-resolution): 2 * segments * (rings - 2) triangles, the same closed body.
    const plumage_host::ProceduralBody coarse(10, 8), fine(200, 100);
    CHECK(coarse.triangle_count() == 128 && coarse.vertex_count() == 9 * 9 + 2);
    CHECK(fine.triangle_count() == 39600);
    coarse.pose_at(1.0, later);
    CHECK(later.size() == coarse.rest_positions().size());
    CHECK(signed_volume(coarse) > 0.3 && std::fabs(signed_volume(fine) - signed_volume(body)) < 0.02 * signed_volume(body));
}

const std::map<std::string, std::function<void()>> kCases = {
    {"skin_u8_normalized_with_ibm", skin_u8_normalized_with_ibm},
    {"skin_u16_float_without_ibm", skin_u16_float_without_ibm},
    {"morph_cube_animated", morph_cube_animated},
    {"morph_weight_precedence", morph_weight_precedence},
    {"morph_cubicspline_weights", morph_cubicspline_weights},
    {"sampler_step", sampler_step},
    {"sampler_linear", sampler_linear},
    {"sampler_cubicspline", sampler_cubicspline},
    {"rotation_shortest_path", rotation_shortest_path},
    {"rotation_cubicspline", rotation_cubicspline},
    {"sparse_positions", sparse_positions},
    {"byte_stride", byte_stride},
    {"quantized_positions", quantized_positions},
    {"hierarchy_matrix_and_trs", hierarchy_matrix_and_trs},
    {"several_primitives", several_primitives},
    {"file_formats", file_formats},
    {"default_mesh_and_clip", default_mesh_and_clip},
    {"refusals", refusals},
    {"procedural_body", procedural_body},
};

}  // namespace

int main(int argc, char** argv) {
    if (argc == 2 && std::string(argv[1]) == "--list") {
        for (const auto& c : kCases) std::printf("%s\n", c.first.c_str());
        return 0;
    }
    if (argc != 3 || kCases.count(argv[1]) == 0) {
        std::fprintf(stderr, "usage: evaluation_test CASE WORK_DIR   (evaluation_test --list)\n");
        return 2;
    }
    g_dir = (std::filesystem::path(argv[2]) / argv[1]).string();
    std::filesystem::create_directories(g_dir);
    try {
        kCases.at(argv[1])();
    } catch (const std::exception& e) {
        check(false, std::string("unexpected exception: ") + e.what(), __LINE__);
    }
    return plumage_check::finish(argv[1]);
}
