// Runs plumage_gltf as a user would and checks what comes out: exit codes,
// one-line reasons, the JSON report and the .glb (read back with tinygltf).
//   host_test HOST_EXE WORK_DIR DATA_DIR SCENARIO
// Scenarios that need ../shared/data exit 77 (ctest SKIP) when it is absent.
#include "gltf_fixture.h"
#include "check.h"

#include <tiny_gltf.h>

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <sstream>
#include <string>
#include <vector>

extern char** environ;

using namespace plumage_test;
using json = nlohmann::json;

namespace {

constexpr int kSkip = 77;

std::string g_host, g_dir, g_data;

using plumage_check::check;
#define CHECK_MSG(cond, msg) check((cond), std::string(#cond) + ": " + (msg), __LINE__)

std::string path(const std::string& name) { return (std::filesystem::path(g_dir) / name).string(); }

std::string slurp(const std::string& file) {
    std::ifstream in(file, std::ios::binary);
    std::ostringstream s;
    s << in.rdbuf();
    return s.str();
}

struct Run {
    int exit_code = -1;
    std::string out;
    std::string err;
};

// Runs the host with `args`, capturing stdout and stderr in files.
Run run_host(const std::vector<std::string>& args) {
    static int counter = 0;
    const std::string base = path("run" + std::to_string(++counter));
    const std::string out_file = base + ".stdout", err_file = base + ".stderr";
    std::vector<std::string> all{g_host};
    all.insert(all.end(), args.begin(), args.end());
    std::vector<char*> argv;
    for (std::string& a : all) argv.push_back(a.data());
    argv.push_back(nullptr);

    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_addopen(&actions, 1, out_file.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    posix_spawn_file_actions_addopen(&actions, 2, err_file.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    pid_t pid = 0;
    const int spawned = posix_spawn(&pid, g_host.c_str(), &actions, nullptr, argv.data(), environ);
    posix_spawn_file_actions_destroy(&actions);
    Run r;
    if (spawned != 0) {
        r.err = "cannot start " + g_host;
        return r;
    }
    int status = 0;
    waitpid(pid, &status, 0);
    r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -WTERMSIG(status);
    r.out = slurp(out_file);
    r.err = slurp(err_file);
    std::string shown;
    for (const std::string& a : args) shown += " " + a;
    std::printf("$ plumage_gltf%s\n  exit %d\n%s%s", shown.c_str(), r.exit_code, r.out.c_str(), r.err.c_str());
    return r;
}

// A refusal: the expected code and exactly one line on stderr naming the reason.
void expect_refusal(const Run& r, int code, const std::string& needle, int line) {
    check(r.exit_code == code, "exit code " + std::to_string(r.exit_code) + ", expected " + std::to_string(code), line);
    const size_t lines = static_cast<size_t>(std::count(r.err.begin(), r.err.end(), '\n'));
    check(lines == 1 && r.err.back() == '\n', "one line on stderr, got: " + r.err, line);
    check(r.err.rfind("plumage_gltf: ", 0) == 0, "the line starts with the program name: " + r.err, line);
    check(r.err.find(needle) != std::string::npos, "the reason mentions \"" + needle + "\": " + r.err, line);
}
#define EXPECT_REFUSAL(run, code, needle) expect_refusal((run), (code), (needle), __LINE__)

bool has_null(const json& j) {
    if (j.is_null()) return true;
    if (j.is_object() || j.is_array()) {
        for (const json& v : j) {
            if (has_null(v)) return true;
        }
    }
    return false;
}

// The report's schema: required keys, one entry per frame, optional sections well formed.
json check_report(const std::string& file, size_t frames) {
    json r;
    try {
        r = json::parse(slurp(file));
    } catch (const std::exception& e) {
        check(false, "report parses: " + std::string(e.what()), __LINE__);
        return r;
    }
    CHECK(r.value("schema", 0) == 1);
    for (const char* key : {"input", "mesh"}) CHECK_MSG(r.contains(key) && r[key].is_string(), key);
    for (const char* key : {"vertices", "triangles", "feathers"}) CHECK_MSG(r.contains(key) && r[key].is_number_unsigned(), key);
    CHECK(r.contains("config") && r["config"].is_object());
    for (const char* key : {"fps", "frames", "mode", "sampler", "seed", "threads", "validate", "flow_axis"}) CHECK_MSG(r["config"].contains(key), key);
    CHECK(r.contains("frames") && r["frames"].is_array() && r["frames"].size() == frames);
    for (const json& f : r["frames"]) {
        for (const char* key : {"index", "time", "step_seconds"}) CHECK_MSG(f.contains(key) && f[key].is_number(), key);
    }
    CHECK(r.contains("summary") && r["summary"].value("frames", size_t{99}) == frames);
    if (frames > 0) CHECK(r["summary"].contains("mean_step_seconds"));
    for (const char* section : {"sampling", "ordering", "static"}) {
        if (r.contains(section)) CHECK_MSG(r[section].is_object() && !has_null(r[section]), section);
    }
    CHECK(!has_null(r["frames"]) && !has_null(r["summary"]));
    if (r.contains("memory")) {
        CHECK(r["memory"].is_object());
        for (const json& phase : r["memory"]) CHECK(phase.is_object() && !phase.empty());
    }
    return r;
}

// The process's memory, read by the host where the platform gives it (Linux, glibc).
void check_memory(const json& r) {
#if defined(__linux__)
    for (const char* phase : {"after_load", "after_create"}) {
        const json m = r.value("memory", json::object()).value(phase, json::object());
        CHECK_MSG(m.contains("rss_kib") && m.contains("peak_rss_kib") && m["rss_kib"] <= m["peak_rss_kib"], phase);
    }
    const json& created = r["memory"]["after_create"];
    CHECK(created["peak_rss_kib"] > r["memory"]["after_load"]["rss_kib"]);
    for (const json& f : r["frames"]) {
        CHECK(f.contains("rss_kib") && f.contains("peak_rss_kib") && f["rss_kib"] > 0 && f["rss_kib"] <= f["peak_rss_kib"]);
        CHECK(f["peak_rss_kib"] >= created["peak_rss_kib"]);
#if defined(__GLIBC__) && !defined(__SANITIZE_ADDRESS__)  // AddressSanitizer's malloc leaves mallinfo2 empty
        CHECK(f.contains("heap_kib") && f["heap_kib"] > 0);
#else
        CHECK(!f.contains("heap_kib") || f["heap_kib"] > 0);
#endif
    }
#else
    (void)r;
#endif
}

// The .glb reads back with tinygltf: a body (and feathers) switching morph targets per frame.
void check_glb(const std::string& file, size_t frames, const json& report) {
    tinygltf::TinyGLTF loader;
    tinygltf::Model m;
    std::string err, warn;
    const bool ok = loader.LoadBinaryFromFile(&m, &err, &warn, file);
    CHECK_MSG(ok, err);
    if (!ok) return;
    const size_t feathers = report.value("feathers", size_t{0});
    CHECK(m.meshes.size() == (feathers > 0 ? 2u : 1u));
    CHECK(!m.meshes.empty() && m.meshes[0].name == "body");
    for (const tinygltf::Mesh& mesh : m.meshes) {
        CHECK(mesh.primitives.size() == 1 && mesh.primitives[0].targets.size() == frames);
    }
    if (!m.meshes.empty()) {
        const int pos = m.meshes[0].primitives[0].attributes.at("POSITION");
        CHECK(m.accessors[static_cast<size_t>(pos)].count == report.value("vertices", size_t{0}));
    }
    if (feathers > 0 && m.meshes.size() == 2) {
        const std::map<std::string, int>& attributes = m.meshes[1].primitives[0].attributes;
        const size_t verts = m.accessors[static_cast<size_t>(attributes.at("POSITION"))].count;
        // The same vertices for every feather: 4 for the kite, more for a segmented shaft.
        CHECK_MSG(verts % feathers == 0 && verts / feathers >= 4, std::to_string(verts) + " vertices for " + std::to_string(feathers) + " feathers");
        for (const char* key : {"NORMAL", "TEXCOORD_0", "_FEATHER_ID"}) {
            CHECK_MSG(attributes.count(key) == 1 && m.accessors[static_cast<size_t>(attributes.at(key))].count == verts, key);
        }
    }
    if (frames == 0) {
        CHECK(m.animations.empty());
        return;
    }
    CHECK(m.animations.size() == 1);
    if (m.animations.size() != 1) return;
    const tinygltf::Animation& a = m.animations[0];
    CHECK(a.samplers.size() == 1 && a.samplers[0].interpolation == "STEP");
    CHECK(m.accessors[static_cast<size_t>(a.samplers[0].input)].count == frames);
    CHECK(a.channels.size() == m.meshes.size());
    for (const tinygltf::AnimationChannel& c : a.channels) CHECK(c.target_path == "weights");
}

// A full run: exit 0, report and .glb checked.
json dress(const std::string& name, std::vector<std::string> args, size_t frames) {
    const std::string glb = path(name + ".glb"), report = path(name + ".json");
    args.insert(args.end(), {"--out", glb, "--report", report});
    const Run r = run_host(args);
    CHECK_MSG(r.exit_code == 0, r.err);
    if (r.exit_code != 0) return json();
    const json j = check_report(report, frames);
    check_glb(glb, frames, j);
    return j;
}

// ---- scenarios ----------------------------------------------------------

int builtin() {
    const json r = dress("builtin", {"--frames", "3", "--validate", "every"}, 3);
    CHECK(r.value("input", "") == "builtin:procedural_body");
    CHECK(r.value("triangles", 0) == 6016);
    // The validation reaches the report with the probes behind coverage.
    const json& f = r["frames"][2];
    CHECK(f.value("coverage_probes", 0) > 0 && f.contains("buried_probes") && f.contains("coverage"));
    check_memory(r);
    return 0;
}

int model_resolution() {
    const json r = dress("resolution", {"--model-resolution", "20,16", "--frames", "2", "--feathers", "300"}, 2);
    CHECK(r.value("triangles", 0) == 2 * 16 * 18 && r.value("vertices", 0) == 19 * 17 + 2);
    CHECK(r.value("feathers", 0) > 0);
    check_memory(r);
    return 0;
}

// Library settings given on the command line reach the library (the report
// echoes the configuration the system was created with).
int settings() {
    const json r = dress("settings", {"--frames", "1", "--curvature-min-scale", "1", "--fluffiness", "10", "--drift-tolerance", "2"}, 1);
    const json& c = r["config"];
    CHECK(c.value("curvature_min_scale", 0.0) == 1.0);
    CHECK(std::fabs(c.value("fluffiness", 0.0) - 10.0 * 3.14159265358979 / 180.0) < 1e-5);
    CHECK(std::fabs(c.value("drift_tolerance", 0.0) - 2.0 * 3.14159265358979 / 180.0) < 1e-5);
    return 0;
}

// The library's per-call figures reach the report, and they agree with
// each other: its own step time within the host's, the neighbourhood time
// within the reordering time, the seeds among the adjusted feathers, and
// at least one adjustment level when feathers were visited, at most one
// per feather.
int frame_figures() {
    const json r = dress("figures", {"--frames", "3", "--validate", "none"}, 3);
    const json& st = r["static"];
    const uint64_t feathers = r.value("feathers", uint64_t{0});
    CHECK_MSG(st.value("levels", uint64_t{0}) >= 1 && st.value("levels", uint64_t{0}) <= feathers, st.dump());
    CHECK(st.contains("clamped") && st.value("neighbourhood_seconds", -1.0) > 0);
    for (const json& f : r["frames"]) {
        for (const char* key : {"deformed", "seeds", "levels", "clamped", "reversals", "reversals_refused", "cycles_broken", "priority_change_percent",
                                "neighbourhood_seconds", "library_step_seconds"}) {
            CHECK_MSG(f.contains(key) && f[key].is_number(), key);
        }
        const uint64_t adjusted = f.value("adjusted", uint64_t{0}), verified = f.value("verified", uint64_t{0}), levels = f.value("levels", uint64_t{0});
        CHECK_MSG(f.value("seeds", uint64_t{0}) <= adjusted, f.dump());
        CHECK_MSG(levels <= feathers && (adjusted + verified == 0 || levels >= 1), f.dump());
        CHECK_MSG(f.value("neighbourhood_seconds", 1.0) <= f.value("reorder_seconds", 0.0), f.dump());
        CHECK_MSG(f.value("library_step_seconds", 1.0) <= f.value("step_seconds", 0.0), f.dump());
    }
    const json& s = r["summary"];
    CHECK(s.value("mean_library_step_seconds", 1.0) <= s.value("mean_step_seconds", 0.0) && s.contains("mean_levels"));
    // A legacy step keeps the neighbourhoods of the first frame.
    const json legacy = dress("figures_legacy", {"--frames", "2", "--validate", "none", "--mode", "legacy"}, 2);
    for (const json& f : legacy["frames"]) CHECK_MSG(f.value("neighbourhood_seconds", 1.0) == 0.0, f.dump());
    return 0;
}

int rest_only() {
    const json r = dress("rest", {"--frames", "0"}, 0);
    CHECK(r["config"].value("frames", 99) == 0);
    return 0;
}

int model(const std::string& file, const std::string& mesh, size_t vertices) {
    const std::string input = (std::filesystem::path(g_data) / file).string();
    if (!std::filesystem::exists(input)) {
        std::printf("SKIPPED: %s not found (the test models live in ../shared/data; set PLUMAGE_DATA_DIR)\n", input.c_str());
        return kSkip;
    }
    const json r = dress(file, {input, "--frames", "3"}, 3);
    CHECK_MSG(r.value("mesh", "") == mesh, r.value("mesh", ""));
    CHECK(r.value("vertices", size_t{0}) == vertices);
    return 0;
}

// A small animated morph cube as .gltf with an external .bin.
GltfFixture cube() {
    GltfFixture f;
    std::vector<float> p, d;
    for (int i = 0; i < 8; ++i) {
        p.insert(p.end(), {static_cast<float>(i & 1), static_cast<float>((i >> 1) & 1), static_cast<float>((i >> 2) & 1)});
        d.insert(d.end(), {0, 0.5f * static_cast<float>((i >> 1) & 1), 0});
    }
    const int pos = f.floats(p, "VEC3");
    const int idx = f.u8({0, 2, 1, 1, 2, 3, 4, 5, 6, 5, 7, 6, 0, 1, 4, 1, 5, 4, 2, 6, 3, 3, 6, 7, 0, 4, 2, 2, 4, 6, 1, 3, 5, 3, 7, 5}, "SCALAR");
    f.add("meshes", {{"name", "cube"}, {"primitives", {{{"attributes", {{"POSITION", pos}}}, {"indices", idx}, {"targets", {{{"POSITION", f.floats(d, "VEC3")}}}}}}}});
    f.single_node_scene(0);
    const int in = f.floats({0, 1}, "SCALAR"), out = f.floats({0, 1}, "SCALAR");
    f.add("animations", {{"name", "stretch"},
                         {"samplers", {{{"input", in}, {"output", out}}}},
                         {"channels", {{{"sampler", 0}, {"target", {{"node", 0}, {"path", "weights"}}}}}}});
    return f;
}

// --start moves the window of frames into the clip; the default frame
// count runs to the end of the clip from there.
int start_window() {
    cube().write(path("cube.gltf"), GltfFormat::External);
    const json r = dress("window", {path("cube.gltf"), "--fps", "4", "--start", "0.5"}, 3);  // 0.5, 0.75 and 1 s of the 1 s clip
    CHECK(r["config"].value("start", 0.0) == 0.5);
    for (size_t k = 0; k < r["frames"].size(); ++k) CHECK(std::fabs(r["frames"][k].value("time", -1.0) - (0.5 + 0.25 * static_cast<double>(k))) < 1e-9);
    const json two = dress("window_two", {path("cube.gltf"), "--fps", "4", "--start", "0.25", "--frames", "2"}, 2);
    CHECK(std::fabs(two["frames"][1].value("time", -1.0) - 0.5) < 1e-9);
    EXPECT_REFUSAL(run_host({path("cube.gltf"), "--start", "2"}), 2, "past the end of clip");
    EXPECT_REFUSAL(run_host({"--start", "-1"}), 2, "--start");
    EXPECT_REFUSAL(run_host({"--start", "nan"}), 2, "--start");
    return 0;
}

int gltf_input() {
    cube().write(path("cube.gltf"), GltfFormat::External);
    const json r = dress("cube_out", {path("cube.gltf"), "--fps", "4"}, 5);  // the whole 1 s clip at 4 fps
    CHECK(r.value("mesh", "") == "cube" && r.value("vertices", 0) == 8);
    return 0;
}

// A flat 24 x 12 quad sheet over x in [0, 2], z in [0, 1] facing +y, with
// two vertex attributes that leave its left half (x < 1) bare: _DENSITY
// (float: 0 left, 1 right) and COLOR_0 (normalized bytes: channel 0 is 1
// everywhere, channel 1 is 0 left and 1 right). _NEGATIVE holds -1;
// _FLOW is (0, 0, 1) in the mesh's space.
GltfFixture sheet() {
    constexpr int nx = 24, nz = 12;
    std::vector<float> p, density, negative, flow;
    std::vector<uint8_t> color;
    for (int k = 0; k <= nz; ++k) {
        for (int i = 0; i <= nx; ++i) {
            const float x = 2.0f * static_cast<float>(i) / nx, z = static_cast<float>(k) / nz;
            p.insert(p.end(), {x, 0.0f, z});
            const bool left = 2 * i < nx;
            density.push_back(left ? 0.0f : 1.0f);
            negative.push_back(-1.0f);
            flow.insert(flow.end(), {0.0f, 0.0f, 1.0f});
            color.insert(color.end(), {255, static_cast<uint8_t>(left ? 0 : 255), 0, 255});
        }
    }
    std::vector<uint16_t> idx;
    for (int k = 0; k < nz; ++k) {
        for (int i = 0; i < nx; ++i) {
            const auto v = [&](int a, int b) { return static_cast<uint16_t>((k + b) * (nx + 1) + i + a); };
            idx.insert(idx.end(), {v(0, 0), v(0, 1), v(1, 0), v(1, 0), v(0, 1), v(1, 1)});
        }
    }
    GltfFixture f;
    const int pos = f.floats(p, "VEC3");
    f.bounds(pos, p, 3);
    const json attributes = {{"POSITION", pos},
                             {"_DENSITY", f.floats(density, "SCALAR")},
                             {"_NEGATIVE", f.floats(negative, "SCALAR")},
                             {"_FLOW", f.floats(flow, "VEC3")},
                             {"COLOR_0", f.u8(color, "VEC4", true)}};
    f.add("meshes", {{"name", "sheet"}, {"primitives", {{{"attributes", attributes}, {"indices", f.u16(idx, "SCALAR")}}}}});
    f.single_node_scene(0);
    return f;
}

// The smallest x of the feathers' corners in a .glb the host wrote (mesh 1, rest pose).
float feathers_min_x(const std::string& file) {
    tinygltf::TinyGLTF loader;
    tinygltf::Model m;
    std::string err, warn;
    if (!loader.LoadBinaryFromFile(&m, &err, &warn, file) || m.meshes.size() < 2) {
        check(false, "feathers in " + file + ": " + err, __LINE__);
        return NAN;
    }
    const tinygltf::Accessor& a = m.accessors[static_cast<size_t>(m.meshes[1].primitives[0].attributes.at("POSITION"))];
    const tinygltf::BufferView& v = m.bufferViews[static_cast<size_t>(a.bufferView)];
    CHECK(a.componentType == kFloat && a.type == TINYGLTF_TYPE_VEC3 && (v.byteStride == 0 || v.byteStride == 12));
    const unsigned char* data = m.buffers[static_cast<size_t>(v.buffer)].data.data() + v.byteOffset + a.byteOffset;
    float min_x = INFINITY;
    for (size_t i = 0; i < a.count; ++i) {
        float x = 0;
        std::memcpy(&x, data + 12 * i, sizeof x);
        min_x = std::min(min_x, x);
    }
    return min_x;
}

// The mean shaft direction (tip - root, normalized) of the feathers in a
// .glb the host wrote (mesh 1, rest pose). The runs here use the
// one-segment feather (`--preset kite`): a kite of 4 vertices, root and tip
// first; the flow does not depend on the shaft.
std::array<double, 3> mean_shaft(const std::string& file, size_t feathers) {
    tinygltf::TinyGLTF loader;
    tinygltf::Model m;
    std::string err, warn;
    std::array<double, 3> sum{};
    if (!loader.LoadBinaryFromFile(&m, &err, &warn, file) || m.meshes.size() < 2 || feathers == 0) {
        check(false, "feathers in " + file + ": " + err, __LINE__);
        return sum;
    }
    const tinygltf::Accessor& a = m.accessors[static_cast<size_t>(m.meshes[1].primitives[0].attributes.at("POSITION"))];
    const tinygltf::BufferView& v = m.bufferViews[static_cast<size_t>(a.bufferView)];
    const unsigned char* data = m.buffers[static_cast<size_t>(v.buffer)].data.data() + v.byteOffset + a.byteOffset;
    const size_t per = 4;
    CHECK_MSG(a.count == per * feathers, std::to_string(a.count) + " vertices for " + std::to_string(feathers) + " feathers");
    if (a.count != per * feathers) return sum;
    for (size_t f = 0; f < feathers; ++f) {
        float root[3], tip[3];
        std::memcpy(root, data + 12 * (f * per), sizeof root);
        std::memcpy(tip, data + 12 * (f * per + 1), sizeof tip);
        for (int c = 0; c < 3; ++c) sum[c] += tip[c] - root[c];
    }
    const double n = std::sqrt(sum[0] * sum[0] + sum[1] * sum[1] + sum[2] * sum[2]);
    for (double& c : sum) c /= n;
    return sum;
}

// A flow map in the mesh's space turns with the node: the sheet's node
// turns it a quarter turn about y, which carries the map's +z to +x, and
// the feathers follow the map rather than the global --flow.
int flow_map() {
    GltfFixture f = sheet();
    const double h = std::sqrt(0.5);
    f.doc()["nodes"][0]["rotation"] = {0.0, h, 0.0, h};
    f.write(path("turned.glb"), GltfFormat::Glb);
    const std::vector<std::string> common = {path("turned.glb"), "--frames", "0", "--feathers", "120", "--flow", "0,0,1", "--preset", "kite"};
    std::vector<std::string> args = common;
    const json plain = dress("turned_plain", args, 0);
    const std::array<double, 3> along_axis = mean_shaft(path("turned_plain.glb"), plain.value("feathers", size_t{0}));
    CHECK_MSG(along_axis[2] > 0.9, std::to_string(along_axis[0]) + "," + std::to_string(along_axis[2]));
    args.insert(args.end(), {"--flow-map", "_FLOW"});
    const json mapped = dress("turned_flow", args, 0);
    CHECK(mapped["config"].value("flow_map", "") == "_FLOW:0");
    const std::array<double, 3> along_map = mean_shaft(path("turned_flow.glb"), mapped.value("feathers", size_t{0}));
    CHECK_MSG(along_map[0] > 0.9, std::to_string(along_map[0]) + "," + std::to_string(along_map[2]));
    args = common;
    args.insert(args.end(), {"--flow-map", "_DENSITY"});
    EXPECT_REFUSAL(run_host(args), 2, "1 components per vertex, 3 needed");
    return 0;
}

// With no flow given, feathers flow from the front of the model (+Z for a
// glTF file, -X for the built-in body) towards its back.
int default_flow() {
    sheet().write(path("front.glb"), GltfFormat::Glb);
    const json sheet_run = dress("front_sheet", {path("front.glb"), "--frames", "0", "--feathers", "120", "--preset", "kite"}, 0);
    CHECK_MSG(sheet_run["config"].contains("flow_source"), sheet_run["config"].dump());
    CHECK(sheet_run["config"]["flow_source"] == json::array({0.0, 0.0, 1.0}));
    const std::array<double, 3> sheet_shaft = mean_shaft(path("front_sheet.glb"), sheet_run.value("feathers", size_t{0}));
    CHECK_MSG(sheet_shaft[2] < -0.3, std::to_string(sheet_shaft[0]) + "," + std::to_string(sheet_shaft[2]));
    const json body = dress("front_builtin", {"--frames", "0", "--feathers", "300", "--preset", "kite"}, 0);
    CHECK_MSG(body["config"]["flow_source"][0] == 0.0, body["config"].dump());
    const std::array<double, 3> body_shaft = mean_shaft(path("front_builtin.glb"), body.value("feathers", size_t{0}));
    CHECK_MSG(body_shaft[0] > 0.5, std::to_string(body_shaft[0]));
    const json given = dress("front_given", {path("front.glb"), "--frames", "0", "--feathers", "120", "--flow", "1,0,0"}, 0);
    CHECK(!given["config"].contains("flow_source"));
    return 0;
}

// --preset scales: the library's scale defaults reach the report, and the
// scales are about half as long as the feathers of the same spacing; the
// default feathers have bent shafts, --preset kite rigid ones.
int preset_scales() {
    const json feathers = dress("preset_feathers", {"--frames", "0", "--feathers", "300"}, 0);
    const json scales = dress("preset_scales", {"--frames", "0", "--feathers", "300", "--preset", "scales"}, 0);
    CHECK(scales["config"]["shaft_segments"] == 2 && scales["config"]["length_per_spacing"] == 2.0);
    CHECK(feathers["config"]["shaft_segments"] == 4 && feathers["config"]["length_per_spacing"] == 4.0);
    CHECK(scales["static"]["intersecting_pairs"] == 0 && scales["static"]["body_penetrations"] == 0);
    const json over = dress("preset_override", {"--frames", "0", "--feathers", "300", "--preset", "scales", "--shaft-segments", "3"}, 0);
    CHECK(over["config"]["shaft_segments"] == 3);
    // --preset kite: the feathers' defaults with rigid shafts; the default
    // bent feathers lie lower than the kites of the same model and seed.
    const json kite = dress("preset_kite", {"--frames", "0", "--feathers", "300", "--preset", "kite"}, 0);
    CHECK(kite["config"]["shaft_segments"] == 1 && kite["config"]["length_per_spacing"] == 4.0);
    CHECK(kite["static"]["intersecting_pairs"] == 0 && kite["static"]["body_penetrations"] == 0);
    CHECK(feathers["static"]["intersecting_pairs"] == 0 && feathers["static"]["body_penetrations"] == 0);
    CHECK(feathers["static"]["tip_height_median"].get<double>() < kite["static"]["tip_height_median"].get<double>());
    // --preset sleek is the default's older name.
    const json sleek = dress("preset_sleek", {"--frames", "0", "--feathers", "300", "--preset", "sleek"}, 0);
    CHECK(sleek["static"]["tip_height_median"] == feathers["static"]["tip_height_median"]);
    return 0;
}

// The defaults lie down (issue #30): the built-in model dressed at
// plumage_config_init's defaults (the host's) has its tips at about a fifth
// of a length, few bristles and closed coverage, collision-free, and its
// tips lie lower than the kite's, measured by the library's validation.
int default_coat_lies_down() {
    const json coat = dress("default_coat", {"--frames", "0", "--feathers", "2000"}, 0);
    const json kite = dress("default_coat_kite", {"--frames", "0", "--feathers", "2000", "--preset", "kite"}, 0);
    const json& s = coat["static"];
    std::printf("default coat: tip median %.3f, p90 %.3f, bristles %.2f %%, coverage %.3f, stack efficiency %.2f\n",
                s["tip_height_median"].get<double>(), s["tip_height_p90"].get<double>(), s["bristle_percent"].get<double>(),
                s["coverage"].get<double>(), s["stack_efficiency"].get<double>());
    CHECK(coat["config"]["shaft_segments"] == 4);
    CHECK(s["intersecting_pairs"] == 0 && s["body_penetrations"] == 0);
    CHECK(s["tip_height_median"].get<double>() <= 0.22 && s["tip_height_p90"].get<double>() <= 0.33);
    CHECK(s["bristle_percent"].get<double>() <= 2.0 && s["coverage"].get<double>() >= 0.98);
    CHECK(s["tip_height_median"].get<double>() <= 0.6 * kite["static"]["tip_height_median"].get<double>());
    CHECK(s["stack_efficiency"].get<double>() < kite["static"]["stack_efficiency"].get<double>());
    return 0;
}

// Per-vertex maps read from vertex attributes reach the library: a spacing
// map of 0 leaves the left half of the sheet bare, whether it comes from a
// float attribute or from one channel of a normalized colour.
int vertex_maps() {
    sheet().write(path("sheet.glb"), GltfFormat::Glb);
    const std::vector<std::string> common = {path("sheet.glb"), "--frames", "0", "--feathers", "120", "--flow", "1,0,0"};
    const auto with = [&](std::vector<std::string> extra) {
        extra.insert(extra.begin(), common.begin(), common.end());
        return extra;
    };
    const json plain = dress("sheet_plain", with({}), 0);
    const float plain_min = feathers_min_x(path("sheet_plain.glb"));
    CHECK_MSG(plain_min < 0.3f, std::to_string(plain_min));
    CHECK(!plain["config"].contains("spacing_map"));
    // Feathers point along +x from their roots, so no corner lies left of a root.
    const json density = dress("sheet_density", with({"--spacing-map", "_DENSITY"}), 0);
    CHECK(density["config"].value("spacing_map", "") == "_DENSITY:0");
    const float density_min = feathers_min_x(path("sheet_density.glb"));
    CHECK_MSG(density_min > 0.9f, std::to_string(density_min));
    CHECK(density.value("feathers", 0) > 0);
    const json colour = dress("sheet_colour", with({"--spacing-map", "COLOR_0:1", "--length-map", "COLOR_0:0", "--width-map", "_DENSITY"}), 0);
    CHECK(colour["config"].value("spacing_map", "") == "COLOR_0:1" && colour["config"].value("width_map", "") == "_DENSITY:0");
    const float colour_min = feathers_min_x(path("sheet_colour.glb"));
    CHECK_MSG(colour_min > 0.9f, std::to_string(colour_min));
    // What cannot be used is refused, with the attribute named.
    EXPECT_REFUSAL(run_host(with({"--spacing-map", "_NOPE"})), 2, "no vertex attribute _NOPE");
    EXPECT_REFUSAL(run_host(with({"--length-map", "_DENSITY:1"})), 2, "1 components per vertex, 2 needed");
    EXPECT_REFUSAL(run_host(with({"--width-map", "_NEGATIVE"})), 4, "width_scale");
    return 0;
}

int truncated() {
    cube().write(path("whole.glb"), GltfFormat::Glb);
    const std::string bytes = slurp(path("whole.glb"));
    std::ofstream(path("truncated.glb"), std::ios::binary) << bytes.substr(0, bytes.size() / 2);
    EXPECT_REFUSAL(run_host({path("truncated.glb")}), 3, "truncated.glb");
    std::ofstream(path("header_only.glb"), std::ios::binary) << bytes.substr(0, 12);
    EXPECT_REFUSAL(run_host({path("header_only.glb")}), 3, "header_only.glb");
    return 0;
}

int not_gltf() {
    std::ofstream(path("notes.glb")) << "these are not the models you are looking for\n";
    EXPECT_REFUSAL(run_host({path("notes.glb")}), 3, "not a glTF file");
    std::ofstream(path("broken.gltf")) << "{\"asset\": {\"version\": \"2.0\"}, \"meshes\": [";
    EXPECT_REFUSAL(run_host({path("broken.gltf")}), 3, "broken.gltf");
    return 0;
}

int missing() {
    EXPECT_REFUSAL(run_host({path("no_such_model.glb")}), 3, "No such file");
    return 0;
}

int unsupported_extension() {
    GltfFixture f = cube();
    f.doc()["extensionsUsed"] = {"KHR_draco_mesh_compression"};
    f.doc()["extensionsRequired"] = {"KHR_draco_mesh_compression"};
    f.write(path("draco.glb"), GltfFormat::Glb);
    EXPECT_REFUSAL(run_host({path("draco.glb")}), 3, "KHR_draco_mesh_compression");
    return 0;
}

int bad_options() {
    const std::vector<std::pair<std::vector<std::string>, std::string>> cases = {
        {{"--bogus"}, "unknown option"},
        {{"--frames", "-1"}, "--frames"},
        {{"--frames", "abc"}, "--frames"},
        {{"--mode", "fast"}, "incremental|legacy|rebuild"},
        {{"--sampler", "grid"}, "guided|random"},
        {{"--validate", "sometimes"}, "every|last|none"},
        {{"--feathers", "10", "--spacing", "0.5"}, "alternatives"},
        {{"--fps", "0"}, "--fps"},
        {{"--flow", "1,2"}, "X,Y,Z"},
        {{"--preset", "fur"}, "feathers|sleek|kite|scales"},
        {{"--theta", "nan"}, "--theta"},
        {{"a.glb", "b.glb"}, "more than one input"},
        {{"--out"}, "missing value"},
        {{"--mesh", "wing"}, "procedural_body"},
        {{"--animation", "fly"}, "swim"},
        {{"--model-resolution", "2,8"}, "RINGS,SEGMENTS"},
        {{"--model-resolution", "10"}, "RINGS,SEGMENTS"},
        {{"--model-resolution", "10,5000"}, "--model-resolution"},
        {{"in.glb", "--model-resolution", "10,8"}, "built-in model only"},
        {{"--spacing-map", "_DENSITY"}, "the built-in model has none"},
        {{"in.glb", "--length-map", "COLOR_0:7"}, "NAME:C"},
        {{"in.glb", "--width-map", ":1"}, "vertex attribute name"},
    };
    for (const auto& c : cases) EXPECT_REFUSAL(run_host(c.first), 2, c.second);
    return 0;
}

int unknown_mesh_in_file() {
    cube().write(path("named.glb"), GltfFormat::Glb);
    EXPECT_REFUSAL(run_host({path("named.glb"), "--mesh", "wing"}), 2, "0:\"cube\"");
    EXPECT_REFUSAL(run_host({path("named.glb"), "--animation", "3"}), 2, "0:\"stretch\"");
    return 0;
}

int library_error() {
    // The host passes parameters through; the library refuses out-of-range ones.
    EXPECT_REFUSAL(run_host({"--threads", "5000", "--frames", "1"}), 4, "INVALID_ARGUMENT");
    EXPECT_REFUSAL(run_host({"--curvature-min-scale", "0", "--frames", "1"}), 4, "curvature_min_scale");
    return 0;
}

// --poses: the library's input for other programs (layout in gltf_host/pose_writer.h;
// the Python package's tests read it back and compare with the .glb).
int poses() {
    const std::string file = path("run.poses");
    const Run r = run_host({"--model-resolution", "20,16", "--frames", "2", "--feathers", "300", "--validate", "none", "--poses", file});
    CHECK_MSG(r.exit_code == 0, r.err);
    CHECK(r.out.find("wrote " + file) != std::string::npos);
    const std::string bytes = slurp(file);
    CHECK(bytes.size() > 56 && bytes.compare(0, 8, std::string("PLMPOSE\0", 8)) == 0);
    if (bytes.size() <= 56) return 0;
    uint32_t version = 0, config_size = 0;
    uint64_t counts[3] = {};
    double fps = 0;
    uint32_t maps = 1;
    std::memcpy(&version, bytes.data() + 8, 4);
    std::memcpy(&config_size, bytes.data() + 12, 4);
    std::memcpy(counts, bytes.data() + 16, 24);
    std::memcpy(&fps, bytes.data() + 40, 8);
    std::memcpy(&maps, bytes.data() + 48, 4);
    const uint64_t nv = 19 * 17 + 2, nt = 2 * 16 * 18, nf = 2;
    CHECK(version == 1 && config_size >= 100 && counts[0] == nv && counts[1] == nt && counts[2] == nf && fps == 30 && maps == 0);
    CHECK(bytes.size() == 56 + config_size + 12 * nv + 12 * nt + 8 * nf + 12 * nv * nf);
    // A skinned model: version 2, the layer map and the skeleton after the other maps.
    const std::string fox = (std::filesystem::path(g_data) / "Fox.glb").string();
    if (std::filesystem::exists(fox)) {
        const Run s = run_host({fox, "--frames", "1", "--feathers", "60", "--validate", "none", "--layer-map", "TEXCOORD_0:1", "--poses", file});
        CHECK_MSG(s.exit_code == 0, s.err);
        const std::string b = slurp(file);
        CHECK(b.size() > 56);
        if (b.size() <= 56) return 0;
        uint64_t c[3] = {};
        std::memcpy(&version, b.data() + 8, 4);
        std::memcpy(c, b.data() + 16, 24);
        std::memcpy(&maps, b.data() + 48, 4);
        CHECK(version == 2 && maps == (16u | 32u) && c[2] == 1);
        const size_t at = 56 + config_size + 12 * c[0] + 12 * c[1] + 8 * c[2] + 4 * c[0];
        CHECK(b.size() > at + 16);
        if (b.size() <= at + 16) return 0;
        uint32_t joints = 0, influences = 0;
        int32_t head = 0;
        std::memcpy(&joints, b.data() + at, 4);
        std::memcpy(&influences, b.data() + at + 4, 4);
        std::memcpy(&head, b.data() + at + 8, 4);
        CHECK(joints == 23 && influences >= 1 && influences <= 4 && head == -1);
        CHECK(b.size() == at + 16 + 16 * joints + 8 * influences * c[0] + 12 * c[0] * c[2]);
        // Feather types: version 3, the types block (count, reserved, presets, one type per vertex) after the skeleton.
        const Run t = run_host({fox, "--frames", "1", "--feathers", "60", "--validate", "none", "--type-map", "TEXCOORD_0:1", "--feather-types",
                                "kite,scales,feathers", "--poses", file});
        CHECK_MSG(t.exit_code == 0, t.err);
        const std::string tb = slurp(file);
        const size_t skeleton_at = 56 + config_size + 12 * c[0] + 12 * c[1] + 8 * c[2];
        const size_t types_at = skeleton_at + 16 + 16 * joints + 8 * influences * c[0];
        CHECK(tb.size() > types_at + 8);
        if (tb.size() <= types_at + 8) return 0;
        std::memcpy(&version, tb.data() + 8, 4);
        std::memcpy(&maps, tb.data() + 48, 4);
        uint32_t type_head[2] = {}, presets[3] = {};
        std::memcpy(type_head, tb.data() + types_at, 8);
        std::memcpy(presets, tb.data() + types_at + 8, 12);
        CHECK(version == 3 && maps == (32u | 64u) && type_head[0] == 3 && type_head[1] == 0);
        CHECK(presets[0] == 3 && presets[1] == 1 && presets[2] == 0);  // PLUMAGE_PRESET_KITE, _SCALES, _FEATHERS
        CHECK(tb.size() == types_at + 8 + 12 + 4 * c[0] + 12 * c[0] * c[2]);
        const Run off = run_host({fox, "--frames", "0", "--feathers", "60", "--validate", "none", "--skeleton-flow", "off", "--poses", file});
        CHECK_MSG(off.exit_code == 0, off.err);
        const std::string v1 = slurp(file);
        CHECK(v1.size() > 56 && v1[8] == 1);  // no skeleton, no layer: version 1 as before
    }
    std::ofstream(path("plain_file")) << "x";  // a file where a directory should be
    EXPECT_REFUSAL(run_host({"--frames", "1", "--poses", path("plain_file") + "/x.poses"}), 1, "cannot write");
    EXPECT_REFUSAL(run_host({"--frames", "1", "--poses="}), 2, "--poses: empty value");
    return 0;
}

// --instances DIR: the manifest and every file it names, sized as it says.
int instances() {
    const std::string dir = path("instances");
    std::filesystem::remove_all(dir);
    const Run r = run_host({"--model-resolution", "20,16", "--frames", "2", "--feathers", "300", "--validate", "none", "--instances", dir});
    CHECK_MSG(r.exit_code == 0, r.err);
    CHECK(r.out.find("wrote " + dir) != std::string::npos);
    json m;
    try {
        m = json::parse(slurp(dir + "/manifest.json"));
    } catch (const std::exception& e) {
        CHECK_MSG(false, e.what());
        return 0;
    }
    const auto size = [&](const json& name) { return std::filesystem::file_size(dir + "/" + name.get<std::string>()); };
    const size_t n = m.value("feathers", size_t{0}), V = m["template"].value("vertices", size_t{0}), T = m["template"].value("triangles", size_t{0});
    const size_t nv = m["body"].value("vertices", size_t{0});
    CHECK(m.value("format", "") == "plumage-instances" && m.value("version", 0) == 1 && m.value("record_bytes", 0) == 36);
    CHECK(n > 200 && V == 13 && T == 14 && m["template"].value("segments", 0) == 4);
    CHECK(m["body"].value("triangles", size_t{0}) == 2 * 16 * 18 && nv > 0);
    CHECK(m["record_layout"]["bends"].value("offset", 0) == 28 && m["record_layout"]["rotation"].value("type", "") == "int16");
    CHECK(size(m["template"]["file"]) == V * (12 + 8 + 4) + T * 12);
    CHECK(size(m["body"]["indices"]) == 2 * 16 * 18 * 12);
    CHECK(m["frames"].size() == 3);
    for (const json& f : m["frames"]) {
        const size_t k = f.value("index", size_t{99});
        CHECK(size(f["records"]) == 36 * n && size(f["body"]) == 12 * nv);
        CHECK(size(f["changed"]) == 4 * f.value("changed_count", size_t{0}));
        CHECK(f.value("all", false) == (k == 0) && (k != 0 || f.value("changed_count", size_t{0}) == n));
        CHECK(f.contains("geometry") == (k == 0 || k == 2));
        if (f.contains("geometry")) CHECK(size(f["geometry"]) == n * V * 32 + n * T * 12);
        CHECK(k == 0 ? f["time"].is_null() : f["time"].is_number());
    }
    std::ofstream(path("plain_file")) << "x";  // a file where a directory should be
    EXPECT_REFUSAL(run_host({"--frames", "1", "--instances", path("plain_file") + "/dir"}), 1, "cannot create directory");
    EXPECT_REFUSAL(run_host({"--frames", "1", "--instances="}), 2, "--instances: empty value");
    return 0;
}

int help() {
    const Run r = run_host({"--help"});
    CHECK(r.exit_code == 0 && r.out.find("usage: plumage_gltf") != std::string::npos && r.err.empty());
    return 0;
}

const std::map<std::string, std::function<int()>> kScenarios = {
    {"builtin", builtin},
    {"rest_only", rest_only},
    {"settings", settings},
    {"model_resolution", model_resolution},
    {"flamingo", [] { return model("Flamingo.glb", "Mesh_0", 715); }},
    {"fox", [] { return model("Fox.glb", "Mesh", 1728); }},
    {"bird", [] { return model("bird.glb", "Plane", 338); }},
    {"gltf_input", gltf_input},
    {"start_window", start_window},
    {"frame_figures", frame_figures},
    {"vertex_maps", vertex_maps},
    {"flow_map", flow_map},
    {"default_flow", default_flow},
    {"preset_scales", preset_scales},
    {"default_coat_lies_down", default_coat_lies_down},
    {"truncated", truncated},
    {"not_gltf", not_gltf},
    {"missing", missing},
    {"unsupported_extension", unsupported_extension},
    {"bad_options", bad_options},
    {"unknown_mesh_in_file", unknown_mesh_in_file},
    {"library_error", library_error},
    {"help", help},
    {"poses", poses},
    {"instances", instances},
};

}  // namespace

int main(int argc, char** argv) {
    if (argc == 2 && std::string(argv[1]) == "--list") {
        for (const auto& s : kScenarios) std::printf("%s\n", s.first.c_str());
        return 0;
    }
    if (argc != 5 || kScenarios.count(argv[4]) == 0) {
        std::fprintf(stderr, "usage: host_test HOST_EXE WORK_DIR DATA_DIR SCENARIO   (host_test --list)\n");
        return 2;
    }
    g_host = argv[1];
    g_dir = (std::filesystem::path(argv[2]) / argv[4]).string();
    g_data = argv[3];
    std::filesystem::remove_all(g_dir);
    std::filesystem::create_directories(g_dir);
    int code = 0;
    try {
        code = kScenarios.at(argv[4])();
    } catch (const std::exception& e) {
        check(false, std::string("unexpected exception: ") + e.what(), __LINE__);
    }
    if (code == kSkip) return kSkip;
    return plumage_check::finish(argv[4]);
}
