// The figures structs' init functions: each sets struct_size to the struct's
// size and zeroes every other byte, ignores NULL, and leaves the struct ready
// for its query on a live system.
#include "plumage.h"

#include "check.h"
#include "sphere_mesh.h"

#include <cstring>
#include <vector>

namespace {

// Fills `s` with garbage, runs `init`, checks struct_size and that the rest is zero.
template <class T>
T initialised(void (*init)(T*), const char* name) {
    T s;
    std::memset(&s, 0xAB, sizeof s);
    init(&s);
    plumage_check::check(s.struct_size == sizeof(T), std::string(name) + ": struct_size = sizeof", __LINE__);
    const unsigned char* bytes = reinterpret_cast<const unsigned char*>(&s);
    bool zero = true;
    for (size_t i = sizeof(uint32_t); i < sizeof(T); ++i) zero = zero && bytes[i] == 0;
    plumage_check::check(zero, std::string(name) + ": every other byte is zero", __LINE__);
    init(nullptr);  // ignored
    return s;
}

}  // namespace

int main() {
    PlumageSamplingStats sampling = initialised(plumage_sampling_stats_init, "sampling stats");
    PlumageOrderingStats ordering = initialised(plumage_ordering_stats_init, "ordering stats");
    PlumageFrameStats frame = initialised(plumage_frame_stats_init, "frame stats");
    PlumageValidation validation = initialised(plumage_validation_init, "validation");

    const SphereMesh sphere;
    PlumageConfig cfg;
    plumage_config_init(&cfg);
    cfg.target_feathers = 120;
    cfg.threads = 1;
    const PlumageMeshDesc mesh = sphere.desc();
    PlumageSystem* sys = nullptr;
    CHECK(plumage_system_create(&cfg, &mesh, &sys) == PLUMAGE_STATUS_OK);
    size_t feathers = 0;
    CHECK(plumage_system_feather_count(sys, &feathers) == PLUMAGE_STATUS_OK && feathers > 0);

    // Straight from init into the queries, which fill every field.
    CHECK(plumage_system_sampling_stats(sys, &sampling) == PLUMAGE_STATUS_OK);
    CHECK(sampling.struct_size == sizeof sampling && sampling.roots == feathers && sampling.spacing > 0.0f);
    CHECK(plumage_system_ordering_stats(sys, &ordering) == PLUMAGE_STATUS_OK);
    CHECK(ordering.struct_size == sizeof ordering && ordering.pairs > 0);
    CHECK(plumage_system_frame_stats(sys, &frame) == PLUMAGE_STATUS_OK);
    CHECK(frame.struct_size == sizeof frame && frame.frame_index == 0 && frame.adjusted == feathers);
    CHECK(plumage_system_validate(sys, &validation) == PLUMAGE_STATUS_OK);
    CHECK(validation.struct_size == sizeof validation && validation.intersecting_pairs == 0 && validation.probes > 0);
    plumage_system_destroy(sys);
    return plumage_check::finish("stats_init_test");
}
