// The busy guard under ThreadSanitizer (issue 36): while one thread steps a
// system, another thread's step, evaluate, query and destroy on it return
// PLUMAGE_STATUS_BUSY without touching it; two threads stepping one system
// at once each get OK or BUSY, never both inside. Built with
// -fsanitize=thread in the normal build (ThreadSanitizer cannot be combined
// with the AddressSanitizer build); a race report fails the test. The Rust
// library itself is not instrumented, so tests/tsan.supp leaves the calls
// made from inside it unjudged (see there); the guard's own proof is in
// tests/busy_guard.rs.
#include <plumage.h>

#include <atomic>
#include <thread>
#include <vector>

#include "check.h"
#include "sphere_mesh.h"

namespace {

// The rendezvous: the stepping thread's progress callback lets the other
// thread make its calls while the step is inside the library.
struct Rendezvous {
    std::atomic<int> stage{0};  // 0 idle, 1 step inside, 2 other thread done
    std::atomic<bool> armed{false};
};

int32_t hold_step(void* user, uint32_t, float) {
    auto* r = static_cast<Rendezvous*>(user);
    if (r->armed.exchange(false)) {
        r->stage.store(1);
        while (r->stage.load() != 2) std::this_thread::yield();
    }
    return 0;
}

PlumageSystem* create(Rendezvous* r, const SphereMesh& sphere) {
    PlumageConfig cfg;
    plumage_config_init(&cfg);
    cfg.threads = 1;
    cfg.target_feathers = 200;
    cfg.progress = hold_step;
    cfg.progress_user_data = r;
    const PlumageMeshDesc mesh = sphere.desc();
    PlumageSystem* sys = nullptr;
    CHECK(plumage_system_create(&cfg, &mesh, &sys) == PLUMAGE_STATUS_OK);
    return sys;
}

}  // namespace

int main() {
    const SphereMesh sphere;
    const std::vector<float>& xyz = sphere.rest;
    std::vector<float> moved(xyz);
    for (size_t i = 0; i < moved.size(); i += 3) moved[i] *= 1.05f;

    // One thread inside a step; the other is refused, destroy included.
    Rendezvous r;
    PlumageSystem* sys = create(&r, sphere);
    if (sys == nullptr) return plumage_check::finish("busy_test");
    uint32_t seen[4] = {};
    std::thread other([&] {
        while (r.stage.load() != 1) std::this_thread::yield();
        size_t n = 0;
        seen[0] = plumage_system_step(sys, moved.data(), SPHERE_VERTICES);
        seen[1] = plumage_system_evaluate(sys, moved.data(), SPHERE_VERTICES);
        seen[2] = plumage_system_feather_count(sys, &n);
        seen[3] = plumage_system_destroy(sys);
        r.stage.store(2);
    });
    r.armed.store(true);
    CHECK(plumage_system_step(sys, moved.data(), SPHERE_VERTICES) == PLUMAGE_STATUS_OK);
    other.join();
    for (uint32_t s : seen) CHECK(s == PLUMAGE_STATUS_BUSY);
    size_t count = 0;
    CHECK(plumage_system_feather_count(sys, &count) == PLUMAGE_STATUS_OK && count > 0);
    CHECK(plumage_system_destroy(sys) == PLUMAGE_STATUS_OK);

    // Two threads stepping one system as fast as they can: each call is OK
    // or BUSY, and the system ends valid.
    Rendezvous idle;
    sys = create(&idle, sphere);
    if (sys == nullptr) return plumage_check::finish("busy_test");
    std::atomic<int> ok{0}, busy{0}, other_status{0};
    auto stepper = [&](const std::vector<float>& pose) {
        for (int k = 0; k < 40; ++k) {
            uint32_t s = plumage_system_step(sys, pose.data(), SPHERE_VERTICES);
            if (s == PLUMAGE_STATUS_OK) ++ok;
            else if (s == PLUMAGE_STATUS_BUSY) ++busy;
            else ++other_status;
        }
    };
    std::thread a(stepper, std::cref(xyz)), b(stepper, std::cref(moved));
    a.join();
    b.join();
    CHECK(ok.load() + busy.load() == 80);
    CHECK(ok.load() >= 40);
    CHECK(other_status.load() == 0);
    std::printf("two steppers: %d OK, %d BUSY\n", ok.load(), busy.load());
    CHECK(plumage_system_feather_count(sys, &count) == PLUMAGE_STATUS_OK && count > 0);
    CHECK(plumage_system_destroy(sys) == PLUMAGE_STATUS_OK);
    return plumage_check::finish("busy_test");
}
