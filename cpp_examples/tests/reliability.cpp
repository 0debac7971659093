// Reliability of the C ABI under hostile use: odd buffers and struct sizes,
// overflowing counts, strange but legal meshes, refused calls followed by
// valid ones, forced panics (test-hook builds), interruption through the
// progress callback, two systems driven from two threads, and saving and
// resuming a frame.
#include "plumage.h"

#include "check.h"
#include "last_error.h"

#include <atomic>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include <unistd.h>

namespace {

struct SystemDeleter {
    void operator()(PlumageSystem* s) const { plumage_system_destroy(s); }
};
using SystemPtr = std::unique_ptr<PlumageSystem, SystemDeleter>;

struct Mesh {
    std::vector<float> positions;
    std::vector<uint32_t> indices;
    PlumageMeshDesc desc() const {
        PlumageMeshDesc d;
        plumage_mesh_desc_init(&d);
        d.positions = positions.data();
        d.vertex_count = positions.size() / 3;
        d.indices = indices.data();
        d.triangle_count = indices.size() / 3;
        return d;
    }
};

// A closed, indexed UV sphere.
Mesh sphere(int rings, int segments, float radius) {
    Mesh m;
    const float pi = 3.14159265358979f;
    m.positions.insert(m.positions.end(), {0, 0, radius});
    for (int r = 1; r < rings; ++r) {
        float th = pi * float(r) / float(rings);
        for (int s = 0; s < segments; ++s) {
            float ph = 2 * pi * float(s) / float(segments);
            m.positions.insert(m.positions.end(), {radius * std::sin(th) * std::cos(ph),
                                                   radius * std::sin(th) * std::sin(ph), radius * std::cos(th)});
        }
    }
    m.positions.insert(m.positions.end(), {0, 0, -radius});
    auto ring = [&](int r, int s) { return uint32_t(1 + (r - 1) * segments + (s % segments)); };
    const uint32_t south = uint32_t(m.positions.size() / 3 - 1);
    for (int s = 0; s < segments; ++s) m.indices.insert(m.indices.end(), {0, ring(1, s), ring(1, s + 1)});
    for (int r = 1; r + 1 < rings; ++r)
        for (int s = 0; s < segments; ++s) {
            m.indices.insert(m.indices.end(), {ring(r, s), ring(r + 1, s), ring(r + 1, s + 1)});
            m.indices.insert(m.indices.end(), {ring(r, s), ring(r + 1, s + 1), ring(r, s + 1)});
        }
    for (int s = 0; s < segments; ++s)
        m.indices.insert(m.indices.end(), {ring(rings - 1, s), south, ring(rings - 1, s + 1)});
    return m;
}

PlumageConfig small_config(uint32_t threads) {
    PlumageConfig cfg;
    plumage_config_init(&cfg);
    cfg.target_feathers = 300;
    cfg.threads = threads;
    return cfg;
}

SystemPtr create(const PlumageConfig* cfg, const Mesh& m) {
    PlumageMeshDesc d = m.desc();
    PlumageSystem* raw = nullptr;
    uint32_t st = plumage_system_create(cfg, &d, &raw);
    if (st != PLUMAGE_STATUS_OK)
        std::fprintf(stderr, "create: %s: %s\n", plumage_status_name(st), last_error(nullptr).c_str());
    return SystemPtr(raw);
}

// The feathers and their triangles, as bytes, for exact comparisons.
std::vector<unsigned char> snapshot(const PlumageSystem* sys) {
    size_t n = 0;
    plumage_system_feathers(sys, nullptr, 0, &n);
    std::vector<PlumageFeather> f(n);
    if (n) plumage_system_feathers(sys, f.data(), f.size(), &n);
    size_t nf = 0;
    plumage_system_feather_triangles(sys, nullptr, 0, &nf);
    std::vector<float> t(nf);
    if (nf) plumage_system_feather_triangles(sys, t.data(), t.size(), &nf);
    std::vector<unsigned char> out(f.size() * sizeof(PlumageFeather) + t.size() * sizeof(float));
    if (!f.empty()) std::memcpy(out.data(), f.data(), f.size() * sizeof(PlumageFeather));
    if (!t.empty()) std::memcpy(out.data() + f.size() * sizeof(PlumageFeather), t.data(), t.size() * sizeof(float));
    return out;
}

// Frame k of a simple animation: a bulge travelling around the sphere.
std::vector<float> frame(const Mesh& m, int k) {
    std::vector<float> p = m.positions;
    for (size_t i = 0; i < p.size(); i += 3) {
        float s = 1.0f + 0.15f * std::sin(3.0f * p[i] + 0.4f * float(k));
        p[i] *= s;
        p[i + 1] *= s;
    }
    return p;
}

void test_buffers_and_sizes() {
    Mesh m = sphere(12, 16, 1.0f);
    PlumageConfig cfg = small_config(1);
    SystemPtr sys = create(&cfg, m);
    CHECK(sys != nullptr);
    if (!sys) return;
    size_t n = 0;
    CHECK(plumage_system_feather_count(sys.get(), &n) == PLUMAGE_STATUS_OK);
    PlumageFeather one[1];
    size_t len = 12345;
    uint32_t st = plumage_system_feathers(sys.get(), one, 0, &len);
    CHECK(len == n);
    CHECK(st == (n == 0 ? PLUMAGE_STATUS_OK : PLUMAGE_STATUS_BUFFER_TOO_SMALL));
    st = plumage_system_feathers(sys.get(), one, 1, &len);
    CHECK(st == (n <= 1 ? PLUMAGE_STATUS_OK : PLUMAGE_STATUS_BUFFER_TOO_SMALL));
    float xyz[1];
    st = plumage_system_feather_triangles(sys.get(), xyz, 1, &len);
    // Nine floats a triangle, at least two triangles (a kite) a feather.
    CHECK(len % 9 == 0 && len >= 18 * n);
    CHECK(st == (n == 0 ? PLUMAGE_STATUS_OK : PLUMAGE_STATUS_BUFFER_TOO_SMALL));
    CHECK(plumage_system_feather_triangles(sys.get(), xyz, 1, nullptr) == PLUMAGE_STATUS_NULL_POINTER);
    if (n > 0) CHECK(!last_error(sys.get()).empty());

    char tiny[1] = {'x'};
    plumage_system_last_error(sys.get(), tiny, 1);
    CHECK(tiny[0] == '\0');
    plumage_system_last_error(sys.get(), tiny, 0);  // capacity 0 writes nothing

    // Output structs: struct_size 0 is refused, far larger is accepted.
    PlumageValidation v{};
    v.struct_size = 0;
    st = plumage_system_validate(sys.get(), &v);
    CHECK(st == PLUMAGE_STATUS_UNSUPPORTED_STRUCT_SIZE || st == PLUMAGE_STATUS_NOT_AVAILABLE);
    struct BigStats {
        PlumageFrameStats stats;
        unsigned char future[256];
    } big;
    std::memset(&big, 0xAB, sizeof big);
    big.stats.struct_size = sizeof big;
    st = plumage_system_frame_stats(sys.get(), &big.stats);
    CHECK(st == PLUMAGE_STATUS_OK || st == PLUMAGE_STATUS_NOT_AVAILABLE);
    if (st == PLUMAGE_STATUS_OK) {
        CHECK(big.stats.struct_size == sizeof(PlumageFrameStats));
        CHECK(big.future[0] == 0xAB);  // nothing written past the known struct
    }
    // Input structs: 0 refused, far larger accepted.
    PlumageMeshDesc d = m.desc();
    PlumageSystem* out = nullptr;
    PlumageConfig c0 = cfg;
    c0.struct_size = 0;
    CHECK(plumage_system_create(&c0, &d, &out) == PLUMAGE_STATUS_UNSUPPORTED_STRUCT_SIZE && out == nullptr);
    struct BigConfig {
        PlumageConfig cfg;
        unsigned char future[512];
    } bc;
    std::memset(&bc, 0xCD, sizeof bc);
    bc.cfg = cfg;
    bc.cfg.struct_size = sizeof bc;
    CHECK(plumage_system_create(&bc.cfg, &d, &out) == PLUMAGE_STATUS_OK);
    plumage_system_destroy(out);
}

void test_overflowing_counts() {
    Mesh m = sphere(6, 8, 1.0f);
    PlumageMeshDesc d = m.desc();
    PlumageSystem* out = nullptr;
    d.vertex_count = SIZE_MAX / 2;
    CHECK(plumage_system_create(nullptr, &d, &out) == PLUMAGE_STATUS_SIZE_OVERFLOW && out == nullptr);
    d = m.desc();
    d.triangle_count = SIZE_MAX / 2;
    CHECK(plumage_system_create(nullptr, &d, &out) == PLUMAGE_STATUS_SIZE_OVERFLOW && out == nullptr);
    CHECK(!last_error(nullptr).empty());
    Mesh bad = m;
    bad.indices.back() = UINT32_MAX;
    d = bad.desc();
    CHECK(plumage_system_create(nullptr, &d, &out) == PLUMAGE_STATUS_INDEX_OUT_OF_RANGE && out == nullptr);
    // A step after a refused create has no system.
    CHECK(plumage_system_step(out, m.positions.data(), m.positions.size() / 3) == PLUMAGE_STATUS_NULL_POINTER);
    SystemPtr sys = create(nullptr, m);
    CHECK(sys != nullptr);
    if (!sys) return;
    CHECK(plumage_system_step(sys.get(), m.positions.data(), SIZE_MAX / 2) == PLUMAGE_STATUS_SIZE_OVERFLOW);
    CHECK(plumage_system_step(sys.get(), m.positions.data(), SIZE_MAX) == PLUMAGE_STATUS_SIZE_OVERFLOW);
    CHECK(plumage_system_step(sys.get(), m.positions.data(), m.positions.size() / 3) == PLUMAGE_STATUS_OK);
}

void test_strange_but_legal_meshes() {
    PlumageConfig cfg = small_config(1);
    cfg.target_feathers = 20;
    // Every face degenerate but one.
    Mesh one;
    one.positions = {0, 0, 0, 1, 0, 0, 0, 1, 0, 2, 0, 0, 3, 0, 0};
    one.indices = {0, 1, 2, 0, 0, 1, 1, 3, 4, 3, 3, 3};
    SystemPtr a = create(&cfg, one);
    CHECK(a != nullptr);
    // A non-manifold fan: four triangles on one edge, plus an isolated vertex and a duplicate face.
    Mesh fan;
    fan.positions = {0, 0, 0, 0, 0, 1, 1, 0, 0, -1, 0, 0, 0, 1, 0, 0, -1, 0, 9, 9, 9};
    fan.indices = {0, 1, 2, 0, 1, 3, 0, 1, 4, 0, 1, 5, 0, 1, 2, 1, 0, 2};
    SystemPtr b = create(&cfg, fan);
    CHECK(b != nullptr);
    if (b) {
        CHECK(plumage_system_step(b.get(), fan.positions.data(), fan.positions.size() / 3) == PLUMAGE_STATUS_OK);
        PlumageValidation v{};
        v.struct_size = sizeof v;
        uint32_t st = plumage_system_validate(b.get(), &v);
        CHECK(st == PLUMAGE_STATUS_OK || st == PLUMAGE_STATUS_NOT_AVAILABLE);
    }
}

void test_refusals_leave_the_system_unchanged() {
    Mesh m = sphere(12, 16, 1.0f);
    PlumageConfig cfg = small_config(2);
    SystemPtr sys = create(&cfg, m);
    CHECK(sys != nullptr);
    if (!sys) return;
    const size_t nv = m.positions.size() / 3;
    std::vector<float> f1 = frame(m, 1);
    CHECK(plumage_system_step(sys.get(), f1.data(), nv) == PLUMAGE_STATUS_OK);
    std::vector<unsigned char> before = snapshot(sys.get());
    std::vector<float> nan = frame(m, 2);
    nan[7] = std::nanf("");
    CHECK(plumage_system_step(sys.get(), nan.data(), nv) == PLUMAGE_STATUS_NON_FINITE);
    CHECK(plumage_system_step(sys.get(), f1.data(), nv - 1) == PLUMAGE_STATUS_VERTEX_COUNT_MISMATCH);
    CHECK(plumage_system_step(sys.get(), nullptr, nv) == PLUMAGE_STATUS_NULL_POINTER);
    CHECK(snapshot(sys.get()) == before);
    // The next valid call works and matches a twin that never saw the refusals.
    SystemPtr twin = create(&cfg, m);
    CHECK(twin != nullptr);
    if (!twin) return;
    std::vector<float> f2 = frame(m, 2);
    CHECK(plumage_system_step(twin.get(), f1.data(), nv) == PLUMAGE_STATUS_OK);
    CHECK(plumage_system_step(twin.get(), f2.data(), nv) == PLUMAGE_STATUS_OK);
    CHECK(plumage_system_step(sys.get(), f2.data(), nv) == PLUMAGE_STATUS_OK);
    CHECK(snapshot(sys.get()) == snapshot(twin.get()));
}

struct StopAfter {
    std::atomic<int> calls{0};
    int allow = 0;
};

int32_t stop_after(void* user, uint32_t phase, float fraction) {
    auto* s = static_cast<StopAfter*>(user);
    if (phase > PLUMAGE_PHASE_ADJUSTING || !(fraction >= 0.0f && fraction <= 1.0f)) return 0;  // counted below
    return s->calls.fetch_add(1) + 1 > s->allow ? 1 : 0;
}

void test_interruption() {
    Mesh m = sphere(16, 24, 1.0f);
    PlumageConfig cfg = small_config(2);
    StopAfter stop;
    stop.allow = 0;
    cfg.progress = stop_after;
    cfg.progress_user_data = &stop;
    PlumageMeshDesc d = m.desc();
    PlumageSystem* out = reinterpret_cast<PlumageSystem*>(0x1);
    CHECK(plumage_system_create(&cfg, &d, &out) == PLUMAGE_STATUS_INTERRUPTED);
    CHECK(out == nullptr);
    CHECK(stop.calls.load() >= 1);
    CHECK(last_error(nullptr).find("interrupted") != std::string::npos);

    // A system whose callback lets create finish, then stops the step.
    stop.calls = 0;
    stop.allow = 1 << 30;
    SystemPtr sys = create(&cfg, m);
    PlumageConfig quiet = small_config(2);
    SystemPtr twin = create(&quiet, m);
    CHECK(sys != nullptr && twin != nullptr);
    if (!sys || !twin) return;
    CHECK(snapshot(sys.get()) == snapshot(twin.get()));
    const size_t nv = m.positions.size() / 3;
    std::vector<unsigned char> before = snapshot(sys.get());
    stop.calls = 0;
    stop.allow = 0;
    std::vector<float> f1 = frame(m, 1);
    CHECK(plumage_system_step(sys.get(), f1.data(), nv) == PLUMAGE_STATUS_INTERRUPTED);
    CHECK(snapshot(sys.get()) == before);
    CHECK(plumage_system_evaluate(sys.get(), f1.data(), nv) == PLUMAGE_STATUS_INTERRUPTED);
    CHECK(snapshot(sys.get()) == before);
    // Let it run again: the same result as the twin that was never stopped.
    stop.allow = 1 << 30;
    CHECK(plumage_system_step(sys.get(), f1.data(), nv) == PLUMAGE_STATUS_OK);
    CHECK(plumage_system_step(twin.get(), f1.data(), nv) == PLUMAGE_STATUS_OK);
    CHECK(snapshot(sys.get()) == snapshot(twin.get()));
}

void test_forced_panic() {
#if defined(PLUMAGE_TEST_HOOKS)
    Mesh m = sphere(8, 12, 1.0f);
    SystemPtr sys = create(nullptr, m);
    CHECK(sys != nullptr);
    if (!sys) return;
    const size_t nv = m.positions.size() / 3;
    CHECK(plumage_testing_is_poisoned(sys.get()) == 0);
    CHECK(plumage_testing_panic_on_next_call(sys.get()) == PLUMAGE_STATUS_OK);
    // Silence: the caught panic writes nothing to the host's stderr.
    std::fflush(stderr);
    std::FILE* captured = std::tmpfile();
    CHECK(captured != nullptr);
    if (!captured) return;
    const int saved_fd = dup(2);
    dup2(fileno(captured), 2);
    const uint32_t panic_status = plumage_system_step(sys.get(), m.positions.data(), nv);
    std::fflush(stderr);
    dup2(saved_fd, 2);
    close(saved_fd);
    const long printed = std::ftell(captured) >= 0 ? (std::fseek(captured, 0, SEEK_END), std::ftell(captured)) : -1;
    std::fclose(captured);
    CHECK(panic_status == PLUMAGE_STATUS_PANIC);
    CHECK(printed == 0);
    CHECK(plumage_testing_is_poisoned(sys.get()) == 1);
    CHECK(last_error(sys.get()).find("panic") != std::string::npos);
    CHECK(plumage_system_step(sys.get(), m.positions.data(), nv) == PLUMAGE_STATUS_POISONED);
    size_t n = 0;
    CHECK(plumage_system_feather_count(sys.get(), &n) == PLUMAGE_STATUS_POISONED);
    PlumageValidation v{};
    v.struct_size = sizeof v;
    CHECK(plumage_system_validate(sys.get(), &v) == PLUMAGE_STATUS_POISONED);
    CHECK(!last_error(sys.get()).empty());
    // destroy (by the unique_ptr) still frees it: ASan's leak check proves it.
#else
    std::printf("forced panic: skipped (library built without the test-hooks feature)\n");
#endif
}

void test_two_threads() {
    Mesh m = sphere(14, 20, 1.0f);
    const size_t nv = m.positions.size() / 3;
    auto run = [&](std::vector<unsigned char>* out) {
        PlumageConfig cfg = small_config(1);
        SystemPtr sys = create(&cfg, m);
        if (!sys) return;
        for (int k = 1; k <= 3; ++k) {
            std::vector<float> f = frame(m, k);
            if (plumage_system_step(sys.get(), f.data(), nv) != PLUMAGE_STATUS_OK) return;
        }
        *out = snapshot(sys.get());
    };
    std::vector<unsigned char> alone, t1, t2;
    run(&alone);
    std::thread a(run, &t1), b(run, &t2);
    a.join();
    b.join();
    CHECK(!alone.empty() || alone == t1);
    CHECK(t1 == alone);
    CHECK(t2 == alone);

    // Concurrent const queries on one system.
    PlumageConfig cfg = small_config(2);
    SystemPtr sys = create(&cfg, m);
    CHECK(sys != nullptr);
    if (!sys) return;
    std::vector<unsigned char> ref = snapshot(sys.get());
    std::atomic<int> mismatches{0};
    auto reader = [&]() {
        for (int i = 0; i < 20; ++i) {
            if (snapshot(sys.get()) != ref) ++mismatches;
            PlumageValidation v{};
            v.struct_size = sizeof v;
            uint32_t st = plumage_system_validate(sys.get(), &v);
            if (st != PLUMAGE_STATUS_OK && st != PLUMAGE_STATUS_NOT_AVAILABLE) ++mismatches;
        }
    };
    std::thread r1(reader), r2(reader);
    r1.join();
    r2.join();
    CHECK(mismatches.load() == 0);
}

// Save a frame, continue, load it back and continue again through the C
// ABI: the frames after the load are byte-identical to those after the
// save. Truncated, corrupt and foreign blobs are refused with INVALID_STATE
// and change nothing.
void test_save_and_resume() {
    Mesh m = sphere(12, 16, 1.0f);
    PlumageConfig cfg = small_config(2);
    SystemPtr sys = create(&cfg, m);
    CHECK(sys != nullptr);
    if (!sys) return;
    const size_t nv = m.positions.size() / 3;
    for (int k = 1; k <= 2; ++k) {
        std::vector<float> f = frame(m, k);
        CHECK(plumage_system_step(sys.get(), f.data(), nv) == PLUMAGE_STATUS_OK);
    }

    // Two-call size query: NULL, then too small, then exact.
    size_t need = 0;
    CHECK(plumage_system_save_state(sys.get(), nullptr, 0, &need) == PLUMAGE_STATUS_BUFFER_TOO_SMALL);
    CHECK(need > 0);
    if (need == 0) return;
    std::vector<uint8_t> blob(need - 1, 0xEE);
    size_t len = 0;
    CHECK(plumage_system_save_state(sys.get(), blob.data(), blob.size(), &len) == PLUMAGE_STATUS_BUFFER_TOO_SMALL);
    CHECK(len == need && blob[0] == 0xEE);
    blob.resize(need);
    CHECK(plumage_system_save_state(sys.get(), blob.data(), blob.size(), &len) == PLUMAGE_STATUS_OK);
    CHECK(len == need);
    CHECK(plumage_system_save_state(sys.get(), blob.data(), blob.size(), nullptr) == PLUMAGE_STATUS_NULL_POINTER);
    const std::vector<unsigned char> at_save = snapshot(sys.get());

    std::vector<std::vector<unsigned char>> first;
    for (int k = 3; k <= 5; ++k) {
        std::vector<float> f = frame(m, k);
        CHECK(plumage_system_step(sys.get(), f.data(), nv) == PLUMAGE_STATUS_OK);
        first.push_back(snapshot(sys.get()));
    }
    CHECK(plumage_system_load_state(sys.get(), blob.data(), blob.size()) == PLUMAGE_STATUS_OK);
    CHECK(snapshot(sys.get()) == at_save);
    PlumageFrameStats fs{};
    fs.struct_size = sizeof fs;
    CHECK(plumage_system_frame_stats(sys.get(), &fs) == PLUMAGE_STATUS_OK && fs.frame_index == 2);
    for (int k = 3; k <= 5; ++k) {
        std::vector<float> f = frame(m, k);
        CHECK(plumage_system_step(sys.get(), f.data(), nv) == PLUMAGE_STATUS_OK);
        CHECK(snapshot(sys.get()) == first[size_t(k - 3)]);
    }

    // Refusals leave the system at frame 5.
    const std::vector<unsigned char> before = snapshot(sys.get());
    CHECK(plumage_system_load_state(sys.get(), blob.data(), blob.size() - 1) == PLUMAGE_STATUS_INVALID_STATE);
    CHECK(!last_error(sys.get()).empty());
    CHECK(plumage_system_load_state(sys.get(), blob.data(), 0) == PLUMAGE_STATUS_INVALID_STATE);
    CHECK(plumage_system_load_state(sys.get(), blob.data(), blob.size() / 2) == PLUMAGE_STATUS_INVALID_STATE);
    std::vector<uint8_t> corrupt = blob;
    corrupt[corrupt.size() / 2] ^= 0x04;
    CHECK(plumage_system_load_state(sys.get(), corrupt.data(), corrupt.size()) == PLUMAGE_STATUS_INVALID_STATE);
    CHECK(plumage_system_load_state(sys.get(), nullptr, blob.size()) == PLUMAGE_STATUS_NULL_POINTER);
    PlumageConfig other_cfg = small_config(2);
    other_cfg.seed = cfg.seed + 1;
    SystemPtr other = create(&other_cfg, m);
    CHECK(other != nullptr);
    if (other) {
        size_t other_len = 0;
        plumage_system_save_state(other.get(), nullptr, 0, &other_len);
        std::vector<uint8_t> foreign(other_len);
        CHECK(plumage_system_save_state(other.get(), foreign.data(), foreign.size(), &other_len) ==
              PLUMAGE_STATUS_OK);
        CHECK(plumage_system_load_state(sys.get(), foreign.data(), foreign.size()) == PLUMAGE_STATUS_INVALID_STATE);
    }
    CHECK(snapshot(sys.get()) == before);
    CHECK(plumage_system_frame_stats(sys.get(), &fs) == PLUMAGE_STATUS_OK && fs.frame_index == 5);
}

}  // namespace

int main() {
    test_buffers_and_sizes();
    test_overflowing_counts();
    test_strange_but_legal_meshes();
    test_refusals_leave_the_system_unchanged();
    test_interruption();
    test_forced_panic();
    test_two_threads();
    test_save_and_resume();
    return plumage_check::finish("reliability");
}
