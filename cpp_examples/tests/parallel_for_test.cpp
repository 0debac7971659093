// A host-supplied parallel-for (PlumageConfig.parallel_for): a system runs
// its parallel work through the host's own threads, here a small
// std::thread-based parallel-for, and its results are byte-identical to
// threads = 1 (create, two steps, evaluate, validation, saved state); so
// are they with a host that runs the tasks one after the other; and with
// threads = 1 the host is never called.
#include "plumage.h"

#include "check.h"
#include "sphere_mesh.h"

#include <cstring>
#include <mutex>
#include <set>
#include <thread>
#include <vector>

namespace {

// What the host saw: how many tasks per call, on which threads they ran,
// and where the progress callbacks came from.
struct HostPool {
    bool serial = false;  // run the tasks one after the other, last first, on the calling thread
    std::mutex lock;
    std::vector<uint32_t> counts;
    std::set<std::thread::id> task_threads;
    std::set<std::thread::id> progress_threads;
};

void parallel_for(void* host_context, uint32_t count, PlumageTaskFn task, void* task_context) {
    HostPool& host = *static_cast<HostPool*>(host_context);
    {
        std::lock_guard<std::mutex> guard(host.lock);
        host.counts.push_back(count);
    }
    const auto run = [&](uint32_t i) {
        {
            std::lock_guard<std::mutex> guard(host.lock);
            host.task_threads.insert(std::this_thread::get_id());
        }
        task(task_context, i);
    };
    if (host.serial) {
        for (uint32_t i = count; i-- > 0;) run(i);
        return;
    }
    std::vector<std::thread> threads;
    for (uint32_t i = 1; i < count; ++i) threads.emplace_back(run, i);
    run(0);  // the calling thread takes a share, as TBB does
    for (std::thread& t : threads) t.join();
}

int32_t progress(void* user, uint32_t, float) {
    HostPool& host = *static_cast<HostPool*>(user);
    std::lock_guard<std::mutex> guard(host.lock);
    host.progress_threads.insert(std::this_thread::get_id());
    return 0;
}

// Every byte a run produced: the feather triangles after create, each step
// and the evaluate, the validation and the saved state at the end.
std::vector<std::vector<unsigned char>> run(uint32_t threads, HostPool* host) {
    const SphereMesh sphere;
    std::vector<float> frame(3 * SPHERE_VERTICES);
    PlumageConfig cfg;
    plumage_config_init(&cfg);
    CHECK(cfg.parallel_for == nullptr && cfg.parallel_for_context == nullptr);  // the library's own threads by default
    cfg.threads = threads;
    cfg.target_feathers = 400;
    if (host != nullptr) {
        cfg.parallel_for = parallel_for;
        cfg.parallel_for_context = host;
        cfg.progress = progress;
        cfg.progress_user_data = host;
    }
    const PlumageMeshDesc mesh = sphere.desc();
    std::vector<std::vector<unsigned char>> out;
    PlumageSystem* sys = nullptr;
    CHECK(plumage_system_create(&cfg, &mesh, &sys) == PLUMAGE_STATUS_OK);
    if (sys == nullptr) return out;
    const auto keep = [&](const void* data, size_t bytes) {
        const auto* p = static_cast<const unsigned char*>(data);
        out.emplace_back(p, p + bytes);
    };
    const auto snapshot = [&] {
        size_t n = 0;
        plumage_system_feather_triangles(sys, nullptr, 0, &n);
        std::vector<float> xyz(n);
        CHECK(plumage_system_feather_triangles(sys, xyz.data(), n, &n) == PLUMAGE_STATUS_OK);
        keep(xyz.data(), xyz.size() * sizeof(float));
    };
    snapshot();
    for (float amount : {0.15f, 0.3f}) {
        sphere_squash(sphere.rest.data(), frame.data(), amount);
        CHECK(plumage_system_step(sys, frame.data(), SPHERE_VERTICES) == PLUMAGE_STATUS_OK);
        snapshot();
    }
    sphere_squash(sphere.rest.data(), frame.data(), 0.1f);
    CHECK(plumage_system_evaluate(sys, frame.data(), SPHERE_VERTICES) == PLUMAGE_STATUS_OK);
    snapshot();
    PlumageValidation v;
    plumage_validation_init(&v);
    CHECK(plumage_system_validate(sys, &v) == PLUMAGE_STATUS_OK);
    CHECK(v.intersecting_pairs == 0 && v.body_penetrations == 0);
    keep(&v, sizeof v);
    size_t n = 0;
    plumage_system_save_state(sys, nullptr, 0, &n);
    std::vector<unsigned char> blob(n);
    CHECK(plumage_system_save_state(sys, blob.data(), blob.size(), &n) == PLUMAGE_STATUS_OK);
    out.push_back(blob);
    plumage_system_destroy(sys);
    return out;
}

}  // namespace

int main() {
    const auto reference = run(1, nullptr);
    CHECK(reference.size() == 6 && !reference[0].empty());

    HostPool threaded;
    CHECK(run(3, &threaded) == reference);
    std::printf("host parallel-for: %zu calls, tasks on %zu threads, progress from %zu threads\n", threaded.counts.size(),
                threaded.task_threads.size(), threaded.progress_threads.size());
    CHECK(!threaded.counts.empty());
    for (uint32_t c : threaded.counts) CHECK(c == 3);  // threads = 3: three tasks a call
    CHECK(threaded.task_threads.size() > 1);
    // Progress comes from the calling thread or from a thread running a task.
    std::set<std::thread::id> allowed = threaded.task_threads;
    allowed.insert(std::this_thread::get_id());
    CHECK(!threaded.progress_threads.empty());
    for (const std::thread::id& id : threaded.progress_threads) CHECK(allowed.count(id) == 1);

    HostPool serial;
    serial.serial = true;
    CHECK(run(4, &serial) == reference);
    CHECK(!serial.counts.empty() && serial.task_threads.size() == 1 && *serial.task_threads.begin() == std::this_thread::get_id());

    HostPool unused;
    CHECK(run(1, &unused) == reference);
    CHECK(unused.counts.empty());  // threads = 1 runs on the calling thread and never calls the host
    return plumage_check::finish("parallel_for_test");
}
