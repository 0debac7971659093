// Threads that fit a host: with PlumageConfig.threads = 1 no worker thread
// is started and every progress callback arrives on the calling thread,
// through create, step, evaluate and validate; with 2 threads the results
// are byte-identical; with threads = 0 all systems share one pool. Threads
// are counted in /proc/self/task (Linux).
#include "plumage.h"

#include "check.h"
#include "sphere_mesh.h"

#include <cstring>
#include <dirent.h>
#include <mutex>
#include <set>
#include <thread>
#include <vector>

namespace {

// Threads of this process, or -1 without /proc.
int thread_count() {
    DIR* d = opendir("/proc/self/task");
    if (d == nullptr) return -1;
    int n = 0;
    while (const dirent* e = readdir(d)) n += e->d_name[0] != '.';
    closedir(d);
    return n;
}

struct Seen {
    std::mutex lock;
    std::set<std::thread::id> callers;
    int calls = 0;
    int most_threads = 0;
};

int32_t record(void* user, uint32_t, float) {
    Seen& seen = *static_cast<Seen*>(user);
    std::lock_guard<std::mutex> guard(seen.lock);
    seen.callers.insert(std::this_thread::get_id());
    ++seen.calls;
    const int n = thread_count();
    if (n > seen.most_threads) seen.most_threads = n;
    return 0;
}

// Creates, steps twice, evaluates and validates with `threads`; returns the
// feather triangles after each call.
std::vector<std::vector<float>> run(uint32_t threads, Seen& seen) {
    const SphereMesh sphere;
    const std::vector<float>& rest = sphere.rest;
    std::vector<float> frame(3 * SPHERE_VERTICES);
    PlumageConfig cfg;
    plumage_config_init(&cfg);
    cfg.threads = threads;
    cfg.target_feathers = 300;
    cfg.progress = record;
    cfg.progress_user_data = &seen;
    const PlumageMeshDesc mesh = sphere.desc();

    std::vector<std::vector<float>> out;
    PlumageSystem* sys = nullptr;
    CHECK(plumage_system_create(&cfg, &mesh, &sys) == PLUMAGE_STATUS_OK);
    if (sys == nullptr) return out;
    auto snapshot = [&] {
        size_t n = 0;
        plumage_system_feather_triangles(sys, nullptr, 0, &n);
        std::vector<float> xyz(n);
        CHECK(plumage_system_feather_triangles(sys, xyz.data(), n, &n) == PLUMAGE_STATUS_OK);
        out.push_back(xyz);
    };
    snapshot();
    for (float amount : {0.15f, 0.3f}) {
        sphere_squash(rest.data(), frame.data(), amount);
        CHECK(plumage_system_step(sys, frame.data(), SPHERE_VERTICES) == PLUMAGE_STATUS_OK);
        snapshot();
    }
    sphere_squash(rest.data(), frame.data(), 0.1f);
    CHECK(plumage_system_evaluate(sys, frame.data(), SPHERE_VERTICES) == PLUMAGE_STATUS_OK);
    snapshot();
    PlumageValidation val;
    std::memset(&val, 0, sizeof val);
    val.struct_size = sizeof val;
    CHECK(plumage_system_validate(sys, &val) == PLUMAGE_STATUS_OK);
    CHECK(val.intersecting_pairs == 0);
    // Validation has no callback: count the threads right after it.
    const int after = thread_count();
    if (after > seen.most_threads) seen.most_threads = after;
    plumage_system_destroy(sys);
    return out;
}

}  // namespace

int main() {
    const int before = thread_count();
    Seen one;
    const auto serial = run(1, one);
    CHECK(one.calls > 0);
    CHECK(one.callers.size() == 1 && *one.callers.begin() == std::this_thread::get_id());
    if (before > 0) {
        std::printf("threads = 1: %d progress calls, at most %d threads in the process (%d before)\n", one.calls,
                    one.most_threads, before);
        CHECK(one.most_threads == before);  // no worker thread started
    }

    Seen two;
    const auto parallel = run(2, two);
    CHECK(two.calls > 0);
    CHECK(parallel == serial);  // byte-identical at any thread count
    CHECK(serial.size() == 4 && !serial[0].empty());  // create, two steps, evaluate

    // threads = 0: every such system shares one pool of all cores, so a
    // second one starts no thread.
    if (before > 0) {
        const SphereMesh sphere;
        const PlumageMeshDesc mesh = sphere.desc();
        PlumageConfig cfg;
        plumage_config_init(&cfg);
        cfg.threads = 0;
        cfg.target_feathers = 100;
        PlumageSystem* a = nullptr;
        PlumageSystem* b = nullptr;
        CHECK(plumage_system_create(&cfg, &mesh, &a) == PLUMAGE_STATUS_OK);
        const int with_one = thread_count();
        CHECK(plumage_system_create(&cfg, &mesh, &b) == PLUMAGE_STATUS_OK);
        const int with_two = thread_count();
        std::printf("threads = 0: %d threads with one system, %d with two (%d before)\n", with_one, with_two, before);
        CHECK(with_one > before);
        CHECK(with_two == with_one);
        plumage_system_destroy(a);
        plumage_system_destroy(b);
    }
    return plumage_check::finish("threads_test");
}
