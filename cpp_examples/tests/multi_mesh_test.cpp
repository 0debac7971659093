// plumage_gltf on a scene of several deforming meshes (--mesh all, several
// --mesh options): two morphed tubes that close in on each other until
// their coats meet, and a static plate that `all` leaves out. Each tube is
// dressed, with its own figures in the report and its own feathers mesh in
// the .glb, and no feather of one crosses a feather of the other.
//   multi_mesh_test HOST_EXE WORK_DIR
#include "check.h"
#include "gltf_fixture.h"

#include <tiny_gltf.h>

#include <sys/wait.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

using namespace plumage_test;
using json = nlohmann::json;

namespace {

std::string g_host, g_dir;

#define CHECK_MSG(cond, msg) ::plumage_check::check((cond), std::string(#cond) + ": " + (msg), __LINE__)

std::string path(const std::string& name) { return (std::filesystem::path(g_dir) / name).string(); }

std::string slurp(const std::string& file) {
    std::ifstream in(file, std::ios::binary);
    std::ostringstream s;
    s << in.rdbuf();
    return s.str();
}

struct Run {
    int exit_code = -1;
    std::string out, err;
};

std::string shell_quoted(const std::string& s) {
    std::string q = "'";
    for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
    return q + "'";
}

Run run_host(const std::vector<std::string>& args) {
    std::string command = shell_quoted(g_host);
    for (const std::string& a : args) command += " " + shell_quoted(a);
    const std::string out = path("run.stdout"), err = path("run.stderr");
    const int status = std::system((command + " >" + shell_quoted(out) + " 2>" + shell_quoted(err)).c_str());
    Run r;
    r.exit_code = status != -1 && WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    r.out = slurp(out);
    r.err = slurp(err);
    std::printf("$ plumage_gltf%s\n  exit %d\n%s%s", command.substr(shell_quoted(g_host).size()).c_str(), r.exit_code, r.out.c_str(), r.err.c_str());
    return r;
}

// Exit code 2 (usage) and one line on stderr that names the reason.
void expect_usage_error(const Run& r, const std::string& needle, int line) {
    ::plumage_check::check(r.exit_code == 2, "exit code " + std::to_string(r.exit_code) + ", expected 2", line);
    ::plumage_check::check(std::count(r.err.begin(), r.err.end(), '\n') == 1, "one line on stderr: " + r.err, line);
    ::plumage_check::check(r.err.find(needle) != std::string::npos, "the reason mentions \"" + needle + "\": " + r.err, line);
}
#define EXPECT_USAGE_ERROR(run, needle) expect_usage_error((run), (needle), __LINE__)

// An open tube of radius 1 along y (0 to 3) around (cx, 0): 24 sides, 10 rings.
void tube(float cx, std::vector<float>& p, std::vector<uint16_t>& idx) {
    constexpr int sides = 24, rings = 10;
    for (int r = 0; r <= rings; ++r) {
        for (int k = 0; k < sides; ++k) {
            const float a = 6.2831853f * static_cast<float>(k) / sides;
            p.insert(p.end(), {cx + std::cos(a), 3.0f * static_cast<float>(r) / rings, std::sin(a)});
        }
    }
    for (int r = 0; r < rings; ++r) {
        for (int k = 0; k < sides; ++k) {
            const auto v = [&](int kk, int rr) { return static_cast<uint16_t>(rr * sides + (kk % sides)); };
            idx.insert(idx.end(), {v(k, r), v(k, r + 1), v(k + 1, r), v(k + 1, r), v(k, r + 1), v(k + 1, r + 1)});
        }
    }
}

// A morphed mesh: its one target moves every vertex by `delta`.
int morphed_tube(GltfFixture& f, const std::string& name, float cx, std::array<float, 3> delta) {
    std::vector<float> p, d;
    std::vector<uint16_t> idx;
    tube(cx, p, idx);
    for (size_t v = 0; v < p.size() / 3; ++v) d.insert(d.end(), delta.begin(), delta.end());
    const int pos = f.floats(p, "VEC3");
    f.bounds(pos, p, 3);
    const int target = f.floats(d, "VEC3");
    f.bounds(target, d, 3);
    return f.add("meshes", {{"name", name},
                            {"primitives", {{{"attributes", {{"POSITION", pos}}}, {"indices", f.u16(idx, "SCALAR")}, {"targets", {{{"POSITION", target}}}}}}}});
}

// tube_a around x = 0 and tube_b around x = 2.6 (a gap of 0.6) moving by
// -0.5 in x over the 1 s clip (to a gap of 0.1, far less than a feather's
// length), tube_a drifting by +0.05; and a static plate far off.
GltfFixture scene(bool with_tubes) {
    GltfFixture f;
    std::vector<int> nodes;
    if (with_tubes) {
        nodes.push_back(f.add("nodes", {{"mesh", morphed_tube(f, "tube_a", 0.0f, {0.05f, 0, 0})}}));
        nodes.push_back(f.add("nodes", {{"mesh", morphed_tube(f, "tube_b", 2.6f, {-0.5f, 0, 0})}}));
    }
    const std::vector<float> plate{10, 0, 0, 11, 0, 0, 10, 0, 1, 11, 0, 1};
    const int pos = f.floats(plate, "VEC3");
    f.bounds(pos, plate, 3);
    const int mesh = f.add("meshes", {{"name", "plate"}, {"primitives", {{{"attributes", {{"POSITION", pos}}}, {"indices", f.u16({0, 2, 1, 1, 2, 3}, "SCALAR")}}}}});
    nodes.push_back(f.add("nodes", {{"mesh", mesh}}));
    f.doc()["scenes"] = json::array({{{"nodes", nodes}}});
    f.doc()["scene"] = 0;
    if (with_tubes) {
        const int in = f.floats({0, 1}, "SCALAR"), out = f.floats({0, 1}, "SCALAR");
        f.add("animations", {{"name", "close_in"},
                             {"samplers", {{{"input", in}, {"output", out}}}},
                             {"channels", {{{"sampler", 0}, {"target", {{"node", 0}, {"path", "weights"}}}}, {{"sampler", 0}, {"target", {{"node", 1}, {"path", "weights"}}}}}}});
    }
    return f;
}

constexpr size_t kFrames = 6;  // 0 to 1 s at 5 fps
constexpr size_t kTubeVertices = 24 * 11, kTubeTriangles = 2 * 24 * 10;

// One run over the scene: the report and the .glb checked mesh by mesh.
json dress(const std::string& name, const std::vector<std::string>& options, const std::vector<std::string>& expected_meshes, bool check_penetrations) {
    const std::string glb = path(name + ".glb"), report = path(name + ".json");
    // The kite (4 vertices a feather, read below); the meshes' coats do not
    // depend on the shaft.
    std::vector<std::string> args{path("scene.glb"), "--fps", "5", "--feathers", "700", "--validate", "every", "--preset", "kite", "--out", glb, "--report", report};
    args.insert(args.end(), options.begin(), options.end());
    const Run r = run_host(args);
    CHECK_MSG(r.exit_code == 0, r.err);
    if (r.exit_code != 0) return json();
    const json j = json::parse(slurp(report));
    CHECK(j["frames"].size() == kFrames);
    // Collision-free among all: no pair in any frame, whatever the mesh.
    CHECK(j["static"]["intersecting_pairs"] == 0);
    for (const json& f : j["frames"]) CHECK_MSG(f["intersecting_pairs"] == 0, "frame " + f["index"].dump());
    if (check_penetrations) CHECK(j["summary"]["max_body_penetrations"] == 0 && j["static"]["body_penetrations"] == 0);
    CHECK(j.contains("meshes") && j["meshes"].size() == expected_meshes.size());
    if (!j.contains("meshes") || j["meshes"].size() != expected_meshes.size()) return j;

    size_t feathers = 0, first_triangle = 0;
    for (size_t m = 0; m < expected_meshes.size(); ++m) {
        const json& part = j["meshes"][m];
        CHECK_MSG(part["name"] == expected_meshes[m], part["name"].dump());
        CHECK(part["vertices"] == kTubeVertices && part["triangles"] == kTubeTriangles && part["first_triangle"] == first_triangle);
        first_triangle += kTubeTriangles;
        const size_t n = part.value("feathers", size_t{0});
        CHECK_MSG(n > 200, std::to_string(n) + " feathers on " + expected_meshes[m]);  // about half of 700 each
        feathers += n;
        CHECK(part["static"]["intersecting_pairs"] == 0 && part["static"]["coverage"] > 0.5);
        CHECK(part["frames"].size() == kFrames);
        for (const json& f : part["frames"]) {
            for (const char* key : {"adjusted", "pops", "pops_percent", "largest_pose_change_deg", "coverage", "tip_height_median", "bristle_percent"}) {
                CHECK_MSG(f.contains(key), key);
            }
            CHECK(f["intersecting_pairs"] == 0 && f["coverage"] > 0.5 && f["tip_height_median"] < 1);
        }
        for (const char* key : {"mean_adjusted", "max_intersecting_pairs", "min_coverage", "max_tip_height_p90", "max_bristle_percent", "mean_pops_percent"}) {
            CHECK_MSG(part["summary"].contains(key), key);
        }
    }
    CHECK(feathers == j["feathers"]);
    // The meshes meet: the closing gap makes the library readjust feathers of both.
    size_t adjusted_a = 0, adjusted_b = 0;
    for (size_t k = 1; k < kFrames; ++k) adjusted_a += j["meshes"][0]["frames"][k].value("adjusted", size_t{0}), adjusted_b += j["meshes"][1]["frames"][k].value("adjusted", size_t{0});
    CHECK_MSG(adjusted_a > 0 && adjusted_b > 0, std::to_string(adjusted_a) + ", " + std::to_string(adjusted_b));

    // The .glb: per mesh a body and its feathers (4 vertices a kite), each
    // with a morph target per frame switched by the one animation.
    tinygltf::TinyGLTF loader;
    tinygltf::Model model;
    std::string err, warn;
    const bool ok = loader.LoadBinaryFromFile(&model, &err, &warn, glb);
    CHECK_MSG(ok, err);
    if (!ok) return j;
    CHECK(model.meshes.size() == 2 * expected_meshes.size());
    if (model.meshes.size() != 2 * expected_meshes.size()) return j;
    std::vector<float> seen_ids;
    for (size_t m = 0; m < expected_meshes.size(); ++m) {
        const tinygltf::Mesh& body = model.meshes[2 * m];
        const tinygltf::Mesh& coat = model.meshes[2 * m + 1];
        CHECK(body.name == expected_meshes[m] && coat.name == expected_meshes[m] + " feathers");
        CHECK(model.accessors[static_cast<size_t>(body.primitives[0].attributes.at("POSITION"))].count == kTubeVertices);
        CHECK(model.accessors[static_cast<size_t>(body.primitives[0].indices)].count == 3 * kTubeTriangles);
        const std::map<std::string, int>& a = coat.primitives[0].attributes;
        const size_t n = j["meshes"][m]["feathers"];
        const size_t verts = model.accessors[static_cast<size_t>(a.at("POSITION"))].count;
        CHECK_MSG(verts == 4 * n, std::to_string(verts) + " vertices for " + std::to_string(n) + " feathers");
        for (const char* key : {"NORMAL", "TEXCOORD_0", "_FEATHER_ID"}) CHECK_MSG(a.count(key) == 1 && model.accessors[static_cast<size_t>(a.at(key))].count == verts, key);
        CHECK(body.primitives[0].targets.size() == kFrames && coat.primitives[0].targets.size() == kFrames);
        // Feather ids are the coat's: distinct across the meshes.
        const tinygltf::Accessor& ids = model.accessors[static_cast<size_t>(a.at("_FEATHER_ID"))];
        const tinygltf::BufferView& view = model.bufferViews[static_cast<size_t>(ids.bufferView)];
        const float* id = reinterpret_cast<const float*>(model.buffers[static_cast<size_t>(view.buffer)].data.data() + view.byteOffset + ids.byteOffset);
        for (size_t v = 0; v < verts; v += 4) seen_ids.push_back(id[v]);
    }
    std::sort(seen_ids.begin(), seen_ids.end());
    CHECK(std::adjacent_find(seen_ids.begin(), seen_ids.end()) == seen_ids.end() && seen_ids.size() == feathers);
    CHECK(model.animations.size() == 1 && model.animations[0].channels.size() == model.meshes.size());
    return j;
}

int run_all() {
    scene(true).write(path("scene.glb"), GltfFormat::Glb);
    // Every deforming mesh (the static plate is left out), incremental:
    // collision-free among all, body penetrations included.
    const json all = dress("all", {"--mesh", "all"}, {"tube_a", "tube_b"}, true);
    // The same listed by name and index, in the order given, rebuilt every frame.
    dress("listed", {"--mesh", "tube_b", "--mesh", "0", "--mode", "rebuild"}, {"tube_b", "tube_a"}, true);

    // One mesh: the output is as before (body and feathers, no `meshes`).
    const Run one = run_host({path("scene.glb"), "--mesh", "tube_a", "--fps", "5", "--frames", "1", "--report", path("one.json")});
    CHECK_MSG(one.exit_code == 0, one.err);
    if (one.exit_code == 0) CHECK(!json::parse(slurp(path("one.json"))).contains("meshes"));

    // Bad --mesh values: a clear reason, exit 2.
    EXPECT_USAGE_ERROR(run_host({path("scene.glb"), "--mesh", "all", "--mesh", "0"}), "give it alone");
    EXPECT_USAGE_ERROR(run_host({path("scene.glb"), "--mesh", "tube_a", "--mesh", "0"}), "already chosen");
    EXPECT_USAGE_ERROR(run_host({path("scene.glb"), "--mesh", "tube_a", "--mesh", "wing"}), "0:\"tube_a\", 1:\"tube_b\", 2:\"plate\"");
    EXPECT_USAGE_ERROR(run_host({path("scene.glb"), "--mesh", "7"}), "no such mesh");
    EXPECT_USAGE_ERROR(run_host({path("scene.glb"), "--mesh="}), "empty value");
    scene(false).write(path("static.glb"), GltfFormat::Glb);
    EXPECT_USAGE_ERROR(run_host({path("static.glb"), "--mesh", "all"}), "no skinned or morphed");
    EXPECT_USAGE_ERROR(run_host({"--mesh", "0", "--mesh", "procedural_body"}), "give --mesh once");
    EXPECT_USAGE_ERROR(run_host({"--mesh", "tail"}), "one mesh, procedural_body");
    return 0;
}

}  // namespace

int main(int argc, char** argv) {
    if (argc != 3) {
        std::fprintf(stderr, "usage: multi_mesh_test HOST_EXE WORK_DIR\n");
        return 2;
    }
    g_host = argv[1];
    g_dir = argv[2];
    std::filesystem::remove_all(g_dir);
    std::filesystem::create_directories(g_dir);
    try {
        run_all();
    } catch (const std::exception& e) {
        ::plumage_check::check(false, std::string("unexpected exception: ") + e.what(), __LINE__);
    }
    return plumage_check::finish("multi_mesh");
}
