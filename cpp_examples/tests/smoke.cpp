// Smoke test of the Plumage C ABI from C++: the contract of the foundation
// issue, including every bad input. Each refusal must come with its own
// status and a message, leave *out NULL, and leave a live system usable.
#include "plumage.h"

#include "check.h"
#include "last_error.h"

#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

namespace {

struct Soup {
    std::vector<float> positions;
    std::vector<uint32_t> indices;
};

// A wavy 6x6 patch as glTF gives it: every triangle has its own vertices.
Soup wavy_patch() {
    Soup s;
    const int n = 6;
    auto z = [](float x, float y) { return 0.1f * std::sin(x) * std::cos(y); };
    for (int j = 0; j < n; ++j) {
        for (int i = 0; i < n; ++i) {
            const float c[6][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 0}, {1, 1}, {0, 1}};
            for (auto& k : c) {
                float x = float(i) + k[0], y = float(j) + k[1];
                s.indices.push_back(uint32_t(s.positions.size() / 3));
                s.positions.insert(s.positions.end(), {x, y, z(x, y)});
            }
        }
    }
    return s;
}

PlumageMeshDesc describe(const Soup& s) {
    PlumageMeshDesc d;
    plumage_mesh_desc_init(&d);
    d.positions = s.positions.data();
    d.vertex_count = s.positions.size() / 3;
    d.indices = s.indices.data();
    d.triangle_count = s.indices.size() / 3;
    return d;
}

void expect_refused(const PlumageConfig* cfg, const PlumageMeshDesc* mesh, uint32_t want, const char* what) {
    PlumageSystem* out = reinterpret_cast<PlumageSystem*>(0x1);
    uint32_t got = plumage_system_create(cfg, mesh, &out);
    std::string msg = last_error(nullptr);
    if (got != want) {
        std::fprintf(stderr, "  %s: got %s, wanted %s (%s)\n", what, plumage_status_name(got),
                     plumage_status_name(want), msg.c_str());
    }
    plumage_check::check(got == want, what, __LINE__);
    plumage_check::check(out == nullptr, "*out is NULL after a refusal", __LINE__);
    plumage_check::check(!msg.empty(), "a refusal leaves a message", __LINE__);
    if (out != nullptr && out != reinterpret_cast<PlumageSystem*>(0x1)) plumage_system_destroy(out);
}

void test_versions() {
    const char* v = plumage_version();
    CHECK(v != nullptr);
    int a = -1, b = -1, c = -1;
    CHECK(std::sscanf(v, "%d.%d.%d", &a, &b, &c) == 3 && a >= 0 && b >= 0 && c >= 0);
    CHECK(plumage_abi_version() == PLUMAGE_ABI_VERSION);
    CHECK(std::strcmp(plumage_status_name(PLUMAGE_STATUS_OK), "OK") == 0);
    CHECK(std::strcmp(plumage_status_name(PLUMAGE_STATUS_PANIC), "PANIC") == 0);
    CHECK(std::strcmp(plumage_status_name(123456u), "UNKNOWN_STATUS") == 0);
    const uint32_t all[] = {PLUMAGE_STATUS_NULL_POINTER, PLUMAGE_STATUS_INVALID_ARGUMENT, PLUMAGE_STATUS_INVALID_MESH,
                            PLUMAGE_STATUS_VERTEX_COUNT_MISMATCH, PLUMAGE_STATUS_BUFFER_TOO_SMALL,
                            PLUMAGE_STATUS_INTERRUPTED, PLUMAGE_STATUS_POISONED, PLUMAGE_STATUS_PANIC};
    for (uint32_t s : all) CHECK(std::strcmp(plumage_status_name(s), "UNKNOWN_STATUS") != 0);
}

void test_bad_meshes() {
    Soup s = wavy_patch();
    PlumageMeshDesc good = describe(s);
    PlumageSystem* out = nullptr;
    CHECK(plumage_system_create(nullptr, &good, nullptr) == PLUMAGE_STATUS_NULL_POINTER);
    expect_refused(nullptr, nullptr, PLUMAGE_STATUS_NULL_POINTER, "NULL mesh");
    PlumageMeshDesc d = good;
    d.positions = nullptr;
    expect_refused(nullptr, &d, PLUMAGE_STATUS_NULL_POINTER, "NULL positions");
    d = good;
    d.indices = nullptr;
    expect_refused(nullptr, &d, PLUMAGE_STATUS_NULL_POINTER, "NULL indices");
    d = good;
    d.vertex_count = 0;
    expect_refused(nullptr, &d, PLUMAGE_STATUS_EMPTY_MESH, "zero vertices");
    d = good;
    d.triangle_count = 0;
    expect_refused(nullptr, &d, PLUMAGE_STATUS_EMPTY_MESH, "zero triangles");
    d = good;
    d.struct_size = 8;
    expect_refused(nullptr, &d, PLUMAGE_STATUS_UNSUPPORTED_STRUCT_SIZE, "struct_size too small");
    for (float bad : {std::nanf(""), std::numeric_limits<float>::infinity(), -std::numeric_limits<float>::infinity()}) {
        Soup t = s;
        t.positions[10] = bad;
        PlumageMeshDesc e = describe(t);
        expect_refused(nullptr, &e, PLUMAGE_STATUS_NON_FINITE, "non-finite position");
    }
    {
        Soup t = s;
        t.indices[4] = uint32_t(t.positions.size() / 3);
        PlumageMeshDesc e = describe(t);
        expect_refused(nullptr, &e, PLUMAGE_STATUS_INDEX_OUT_OF_RANGE, "index == vertex_count");
        t.indices[4] = UINT32_MAX;
        e = describe(t);
        expect_refused(nullptr, &e, PLUMAGE_STATUS_INDEX_OUT_OF_RANGE, "index UINT32_MAX");
    }
    {
        Soup t;
        t.positions = {0, 0, 0, 1, 1, 1, 2, 2, 2, 3, 3, 3};
        t.indices = {0, 1, 2, 1, 2, 3, 0, 0, 1};
        PlumageMeshDesc e = describe(t);
        expect_refused(nullptr, &e, PLUMAGE_STATUS_DEGENERATE_MESH, "all triangles degenerate");
    }
    {
        // Some degenerate triangles among good ones are ignored.
        Soup t = s;
        t.indices.insert(t.indices.end(), {0, 0, 0, 1, 1, 2});
        PlumageMeshDesc e = describe(t);
        CHECK(plumage_system_create(nullptr, &e, &out) == PLUMAGE_STATUS_OK);
        plumage_system_destroy(out);
        out = nullptr;
    }
    {
        // A struct_size larger than the library knows is accepted.
        struct Bigger {
            PlumageMeshDesc mesh;
            double future[4];
        } big{};
        big.mesh = good;
        big.mesh.struct_size = sizeof(Bigger);
        CHECK(plumage_system_create(nullptr, &big.mesh, &out) == PLUMAGE_STATUS_OK);
        plumage_system_destroy(out);
        out = nullptr;
    }
    PlumageConfig cfg;
    plumage_config_init(&cfg);
    CHECK(cfg.struct_size == sizeof(PlumageConfig));
    PlumageConfig bad = cfg;
    bad.struct_size = 0;
    expect_refused(&bad, &good, PLUMAGE_STATUS_UNSUPPORTED_STRUCT_SIZE, "config struct_size 0");
    bad = cfg;
    bad.mode = 99;
    expect_refused(&bad, &good, PLUMAGE_STATUS_INVALID_ARGUMENT, "unknown mode");
    bad = cfg;
    bad.theta = std::nanf("");
    expect_refused(&bad, &good, PLUMAGE_STATUS_NON_FINITE, "NaN theta");
    CHECK(plumage_system_create(&cfg, &good, &out) == PLUMAGE_STATUS_OK);
    plumage_system_destroy(out);
}

void test_live_system() {
    Soup s = wavy_patch();
    PlumageMeshDesc d = describe(s);
    PlumageSystem* sys = nullptr;
    CHECK(plumage_system_create(nullptr, &d, &sys) == PLUMAGE_STATUS_OK);
    CHECK(sys != nullptr);
    if (!sys) return;
    size_t n = 0;
    CHECK(plumage_system_vertex_count(sys, &n) == PLUMAGE_STATUS_OK);
    CHECK(n == s.positions.size() / 3);
    CHECK(plumage_system_step(sys, s.positions.data(), n) == PLUMAGE_STATUS_OK);

    CHECK(plumage_system_step(nullptr, s.positions.data(), n) == PLUMAGE_STATUS_NULL_POINTER);
    CHECK(plumage_system_step(sys, nullptr, n) == PLUMAGE_STATUS_NULL_POINTER);
    CHECK(!last_error(sys).empty());
    CHECK(plumage_system_step(sys, s.positions.data(), n - 3) == PLUMAGE_STATUS_VERTEX_COUNT_MISMATCH);
    CHECK(plumage_system_evaluate(sys, s.positions.data(), n + 1) == PLUMAGE_STATUS_VERTEX_COUNT_MISMATCH);
    CHECK(plumage_system_step(sys, s.positions.data(), SIZE_MAX / 2) == PLUMAGE_STATUS_SIZE_OVERFLOW);
    std::vector<float> nan = s.positions;
    nan[5] = std::nanf("");
    CHECK(plumage_system_step(sys, nan.data(), n) == PLUMAGE_STATUS_NON_FINITE);
    CHECK(plumage_system_evaluate(sys, nan.data(), n) == PLUMAGE_STATUS_NON_FINITE);
    CHECK(last_error(sys).find("non-finite") != std::string::npos);

    size_t count = 99;
    CHECK(plumage_system_feather_count(sys, &count) == PLUMAGE_STATUS_OK);
    CHECK(plumage_system_feather_count(sys, nullptr) == PLUMAGE_STATUS_NULL_POINTER);
    CHECK(plumage_system_feather_count(nullptr, &count) == PLUMAGE_STATUS_NULL_POINTER);
    size_t len = 0;
    CHECK(plumage_system_feathers(sys, nullptr, 0, nullptr) == PLUMAGE_STATUS_NULL_POINTER);
    uint32_t st = plumage_system_feathers(sys, nullptr, 0, &len);
    CHECK(len == count);
    CHECK(st == (count == 0 ? PLUMAGE_STATUS_OK : PLUMAGE_STATUS_BUFFER_TOO_SMALL));
    PlumageValidation val{};
    val.struct_size = 2;
    st = plumage_system_validate(sys, &val);
    CHECK(st == PLUMAGE_STATUS_UNSUPPORTED_STRUCT_SIZE || st == PLUMAGE_STATUS_NOT_AVAILABLE);

    // After every refusal the next valid call works.
    std::vector<float> moved = s.positions;
    for (size_t i = 2; i < moved.size(); i += 3) moved[i] += 0.05f;
    CHECK(plumage_system_step(sys, moved.data(), n) == PLUMAGE_STATUS_OK);
    CHECK(plumage_system_evaluate(sys, s.positions.data(), n) == PLUMAGE_STATUS_OK);
    plumage_system_destroy(sys);
    plumage_system_destroy(nullptr);
}

void test_last_error_buffer() {
    PlumageSystem* out = nullptr;
    CHECK(plumage_system_create(nullptr, nullptr, &out) == PLUMAGE_STATUS_NULL_POINTER);
    size_t need = plumage_system_last_error(nullptr, nullptr, 0);
    CHECK(need > 1);
    char small[3] = {'x', 'x', 'x'};
    CHECK(plumage_system_last_error(nullptr, small, sizeof small) == need);
    CHECK(small[2] == '\0');
}

}  // namespace

int main() {
    test_versions();
    test_bad_meshes();
    test_live_system();
    test_last_error_buffer();
    return plumage_check::finish("smoke");
}
