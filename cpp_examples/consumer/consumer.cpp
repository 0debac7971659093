// C++17 consumer of an installed Plumage through plumage.hpp (find_package,
// Plumage::plumage): dresses a sphere, steps a frame, validates it, copies
// the geometry out, and shows that refusals arrive as plumage::Error and
// leave the system usable. No status is checked by hand. Exit 0 on success.
#include <plumage.hpp>

#include "sphere.h"

#include <cmath>
#include <cstdio>
#include <cstring>
#include <vector>

namespace {

int failures = 0;

void expect(bool ok, const char* what) {
    if (!ok) {
        std::fprintf(stderr, "consumer.cpp: FAILED: %s\n", what);
        ++failures;
    }
}

template <class F>
uint32_t status_of(F&& f) {
    try {
        f();
    } catch (const plumage::Error& e) {
        expect(!e.message().empty(), "an Error carries the library's message");
        expect(std::strstr(e.what(), e.status_name()) != nullptr, "what() names the status");
        return e.status();
    }
    return PLUMAGE_STATUS_OK;
}

}  // namespace

int main() try {
    expect(plumage::abi_compatible(), "library ABI = header ABI");
    std::vector<float> rest(3 * SPHERE_VERTICES), frame(3 * SPHERE_VERTICES);
    std::vector<uint32_t> tri(3 * SPHERE_TRIANGLES);
    sphere_fill(rest.data(), tri.data());
    sphere_squash(rest.data(), frame.data(), 0.2f);

    PlumageConfig cfg = plumage::default_config();
    cfg.target_feathers = 150;
    cfg.threads = 2;
    plumage::System created(cfg, rest, tri);
    plumage::System sys = std::move(created);  // move-only handle
    expect(!created && sys, "a moved System leaves the source empty");
    expect(sys.vertex_count() == SPHERE_VERTICES, "vertex count");

    sys.step(frame);
    const PlumageValidation val = sys.validate();
    const size_t n = sys.feather_count();
    expect(n >= 50, "at least 50 feathers");
    expect(val.intersecting_pairs == 0, "0 intersecting pairs after a step");
    expect(sys.frame_stats().frame_index == 1, "frame index 1 after one step");
    expect(sys.part_stats(0, SPHERE_TRIANGLES).feathers == n, "the part of every triangle holds every feather");
    expect(sys.validate_part(0, SPHERE_TRIANGLES).intersecting_pairs == 0, "a part's validation");
    expect(status_of([&] { sys.part_stats(1, SPHERE_TRIANGLES); }) == PLUMAGE_STATUS_INDEX_OUT_OF_RANGE,
           "a part past the triangles throws INDEX_OUT_OF_RANGE");

    const std::vector<PlumageFeather> feathers = sys.feathers();
    expect(feathers.size() == n, "one PlumageFeather per feather");
    const size_t floats = sys.feather_triangles().size();
    expect(floats % 9 == 0 && floats >= 18 * n, "nine floats a triangle, at least two triangles a feather");
    const plumage::FeatherGeometry g = sys.feather_geometry();
    expect(g.feather_count() == n, "geometry: one entry per feather");
    expect(floats == 3 * g.indices.size(), "the geometry's triangles are the copied-out ones");
    expect(g.positions.size() == 3 * g.vertex_count() && g.uvs.size() == 2 * g.vertex_count(), "geometry sizes");
    bool unit = true;
    for (size_t i = 0; i < g.vertex_count(); ++i) {
        const float* v = &g.normals[3 * i];
        unit = unit && std::fabs(std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]) - 1.0f) < 1e-3f;
    }
    expect(unit, "geometry normals are unit length");
    bool in_range = true;
    for (uint32_t idx : g.indices) in_range = in_range && idx < g.vertex_count();
    expect(in_range, "geometry indices index the vertex array");

    // Refusals: an exception with the status; the system is as it was.
    const std::vector<uint8_t> saved = sys.save_state();
    std::vector<float> short_frame(frame.begin(), frame.end() - 3);
    expect(status_of([&] { sys.step(short_frame); }) == PLUMAGE_STATUS_VERTEX_COUNT_MISMATCH,
           "a frame with a vertex missing throws VERTEX_COUNT_MISMATCH");
    expect(sys.save_state() == saved, "a refused step leaves the system as it was");
    expect(status_of([&] { sys.load_state(saved.data(), saved.size() / 2); }) == PLUMAGE_STATUS_INVALID_STATE,
           "a truncated blob throws INVALID_STATE");
    std::vector<uint32_t> bad_tri = tri;
    bad_tri[4] = SPHERE_VERTICES;
    expect(status_of([&] { plumage::System refused(cfg, rest, bad_tri); }) == PLUMAGE_STATUS_INDEX_OUT_OF_RANGE,
           "a create with an index past the vertices throws INDEX_OUT_OF_RANGE");

    // Save, step, load, step again: byte-identical feathers.
    sphere_squash(rest.data(), frame.data(), 0.3f);
    sys.step(frame);
    const std::vector<float> first = sys.feather_triangles();
    sys.load_state(saved);
    sys.step(frame);
    expect(sys.feather_triangles() == first, "a loaded state steps to the same feathers");

    std::printf("plumage %s via plumage.hpp: %zu feathers, %zu geometry vertices, %llu intersecting pairs, %s\n",
                plumage::version(), n, g.vertex_count(), static_cast<unsigned long long>(val.intersecting_pairs),
                failures == 0 ? "all checks passed" : "FAILED");
    return failures == 0 ? 0 : 1;
} catch (const plumage::Error& e) {
    std::fprintf(stderr, "consumer.cpp: unexpected %s\n", e.what());
    return 1;
}
