// An engine's frame loop around Plumage, as a game would write it: a
// deforming mesh of its own (capsule.h: a limb of 4 992 triangles waving
// with a sine), one system with threads = 1 (no thread of the library's
// own: it runs inside the engine's frame), created with the library's
// defaults or the kite preset. Each frame it steps the system, then pulls
// what a renderer uploads:
//   - the instancing records (plumage_system_feather_instances, 36 bytes a
//     feather), copying only those of the feathers in
//     plumage_system_changed_feathers into its own persistent "GPU" buffer,
//     one copy per run of consecutive indices, as glBufferSubData ranges;
//   - for comparison, what a full-geometry upload would be: the positions
//     and normals of plumage_system_feather_geometry.
// It prints the step time per frame (mean, p95), the bytes a frame uploads
// both ways, and checks after every frame that its buffer equals a full
// copy of the records (the changed list missed nothing): exit 1 if not.
//
//   plumage_engine_example [--preset default|kite] [--feathers N] [--frames N]
//                          [--wave whole|far-half] [--seed S] [--per-frame] [--validate]
#include "plumage.hpp"

#include "capsule.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <string>
#include <vector>

namespace {

struct Options {
    bool kite = false;
    uint32_t feathers = 2000;
    uint32_t frames = 120;
    engine::Wave wave = engine::Wave::Whole;
    uint64_t seed = 1;
    bool per_frame = false;
    bool validate = false;
};

const char* const USAGE =
    "usage: plumage_engine_example [--preset default|kite] [--feathers N] [--frames N]\n"
    "                              [--wave whole|far-half] [--seed S] [--per-frame] [--validate]\n"
    "  --preset     the library's defaults (plumage_config_init, bent feathers) or PLUMAGE_PRESET_KITE\n"
    "  --feathers   target feather count (default 2000)    --frames  frames at 60 fps (default 120)\n"
    "  --wave       whole: every vertex moves (default); far-half: the near half is held still\n"
    "  --per-frame  a line per frame    --validate  the library's exact checks after the last frame (untimed)\n";

[[noreturn]] void usage_error(const std::string& what) {
    std::fprintf(stderr, "plumage_engine_example: %s\n%s", what.c_str(), USAGE);
    std::exit(2);
}

uint64_t parse_count(const char* flag, const char* text, uint64_t least) {
    char* end = nullptr;
    const unsigned long long v = std::strtoull(text, &end, 10);
    if (end == text || *end != '\0' || text[0] == '-' || v < least) {
        usage_error(std::string(flag) + " wants a whole number >= " + std::to_string(least) + ", not '" + text + "'");
    }
    return v;
}

Options parse(int argc, char** argv) {
    Options o;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        if (a == "--help" || a == "-h") {
            std::fputs(USAGE, stdout);
            std::exit(0);
        }
        if (a == "--per-frame") {
            o.per_frame = true;
            continue;
        }
        if (a == "--validate") {
            o.validate = true;
            continue;
        }
        if (i + 1 >= argc) usage_error(a == "--preset" || a == "--feathers" || a == "--frames" || a == "--wave" || a == "--seed"
                                           ? a + " wants a value"
                                           : "unknown option '" + a + "'");
        const char* v = argv[++i];
        if (a == "--preset") {
            if (std::strcmp(v, "default") == 0) {
                o.kite = false;
            } else if (std::strcmp(v, "kite") == 0) {
                o.kite = true;
            } else {
                usage_error(std::string("--preset is default or kite, not '") + v + "'");
            }
        } else if (a == "--feathers") {
            o.feathers = static_cast<uint32_t>(std::min<uint64_t>(parse_count("--feathers", v, 1), PLUMAGE_MAX_FEATHERS));
        } else if (a == "--frames") {
            o.frames = static_cast<uint32_t>(std::min<uint64_t>(parse_count("--frames", v, 1), 1000000));
        } else if (a == "--wave") {
            if (std::strcmp(v, "whole") == 0) {
                o.wave = engine::Wave::Whole;
            } else if (std::strcmp(v, "far-half") == 0) {
                o.wave = engine::Wave::FarHalf;
            } else {
                usage_error(std::string("--wave is whole or far-half, not '") + v + "'");
            }
        } else if (a == "--seed") {
            o.seed = parse_count("--seed", v, 0);
        } else {
            usage_error("unknown option '" + a + "'");
        }
    }
    return o;
}

// A refused C call (the wrapper has no geometry query for two buffers alone).
void check(uint32_t status, const PlumageSystem* sys) {
    if (status == PLUMAGE_STATUS_OK) return;
    char msg[512];
    plumage_system_last_error(sys, msg, sizeof msg);
    throw plumage::Error(status, msg);
}

double seconds_since(std::chrono::steady_clock::time_point t0) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

double mean(const std::vector<double>& v) {
    double s = 0.0;
    for (double x : v) s += x;
    return v.empty() ? 0.0 : s / static_cast<double>(v.size());
}

// The 95th percentile: the smallest value at least 95 % of the samples are at or below.
double p95(std::vector<double> v) {
    if (v.empty()) return 0.0;
    std::sort(v.begin(), v.end());
    const size_t rank = static_cast<size_t>(std::ceil(0.95 * static_cast<double>(v.size())));
    return v[std::max<size_t>(rank, 1) - 1];
}

// The renderer's side: the persistent instance buffer, written only where
// the changed list says. Returns the ranges (glBufferSubData calls) made.
size_t upload_changed(std::vector<PlumageFeatherInstance>& gpu, const std::vector<PlumageFeatherInstance>& records,
                      const std::vector<uint32_t>& changed, bool all) {
    if (all) {
        std::memcpy(gpu.data(), records.data(), records.size() * sizeof(PlumageFeatherInstance));
        return 1;
    }
    size_t ranges = 0;
    for (size_t i = 0; i < changed.size();) {
        size_t j = i + 1;
        while (j < changed.size() && changed[j] == changed[j - 1] + 1) ++j;
        // glBufferSubData(GL_ARRAY_BUFFER, first * 36, (j - i) * 36, &records[first])
        const size_t first = changed[i];
        std::memcpy(&gpu[first], &records[first], (j - i) * sizeof(PlumageFeatherInstance));
        ++ranges;
        i = j;
    }
    return ranges;
}

}  // namespace

int main(int argc, char** argv) {
    const Options opt = parse(argc, argv);
    const engine::Capsule body = engine::make_capsule();
    engine::Limb limb(body, opt.wave);
    std::vector<float> positions;
    limb.pose(0.0, positions);  // the rest (bind) pose: the straight limb

    PlumageConfig cfg;
    if (opt.kite) {
        plumage_config_init_preset(&cfg, PLUMAGE_PRESET_KITE);
    } else {
        plumage_config_init(&cfg);
    }
    cfg.threads = 1;
    cfg.target_feathers = opt.feathers;
    cfg.seed = opt.seed;
    const char* preset = opt.kite ? "kite" : "default";
    const char* wave = opt.wave == engine::Wave::Whole ? "whole" : "far-half";

    try {
        const auto t_create = std::chrono::steady_clock::now();
        plumage::System sys(cfg, positions, body.indices);
        const double create_s = seconds_since(t_create);
        const size_t n = sys.feather_count();

        // Uploaded once: the template card (and, for a full-geometry path,
        // its indices and UVs, which never change either).
        const plumage::FeatherTemplate card = sys.feather_template();

        // The first upload: create lists every feather.
        std::vector<PlumageFeatherInstance> records;
        std::vector<uint32_t> changed;
        sys.feather_instances(records);
        std::vector<PlumageFeatherInstance> gpu(records.size());
        const bool all_after_create = sys.changed_feathers(changed);
        upload_changed(gpu, records, changed, all_after_create);

        // The full-geometry path pulls positions and normals only.
        PlumageFeatherGeometry geo;
        plumage_feather_geometry_init(&geo);
        check(plumage_system_feather_geometry(sys.get(), &geo), sys.get());
        std::vector<float> geo_positions(3 * static_cast<size_t>(geo.vertex_count));
        std::vector<float> geo_normals(geo_positions.size());
        const size_t geometry_bytes = (geo_positions.size() + geo_normals.size()) * sizeof(float);

        std::printf("engine_example: capsule of %zu triangles, %zu vertices, wave %s; preset %s (S = %u), threads = 1\n",
                    body.triangle_count(), body.vertex_count(), wave, preset, card.segments);
        std::printf("  %zu feathers (asked %u), created in %.3f s; card %zu vertices, %zu triangles (uploaded once)\n", n,
                    opt.feathers, create_s, card.vertex_count(), card.triangle_count());

        std::vector<double> step_ms, pull_ms, geometry_ms, listed, record_bytes, ranges, adjusted;
        size_t frames_all = 0, mismatched_frames = 0;
        uint32_t first_mismatch = 0;
        const auto t_loop = std::chrono::steady_clock::now();
        const std::clock_t cpu_loop = std::clock();
        for (uint32_t f = 1; f <= opt.frames; ++f) {
            limb.pose(f / 60.0, positions);

            const auto t_step = std::chrono::steady_clock::now();
            sys.step(positions);
            step_ms.push_back(1e3 * seconds_since(t_step));

            const auto t_pull = std::chrono::steady_clock::now();
            sys.feather_instances(records);
            const bool all = sys.changed_feathers(changed);
            const size_t made = upload_changed(gpu, records, changed, all);
            pull_ms.push_back(1e3 * seconds_since(t_pull));
            const size_t count = all ? records.size() : changed.size();
            listed.push_back(static_cast<double>(count));
            record_bytes.push_back(static_cast<double>(count * sizeof(PlumageFeatherInstance)));
            ranges.push_back(static_cast<double>(made));
            frames_all += all;

            const auto t_geo = std::chrono::steady_clock::now();
            geo.positions = geo_positions.data();
            geo.positions_capacity = geo_positions.size();
            geo.normals = geo_normals.data();
            geo.normals_capacity = geo_normals.size();
            check(plumage_system_feather_geometry(sys.get(), &geo), sys.get());
            geometry_ms.push_back(1e3 * seconds_since(t_geo));

            adjusted.push_back(static_cast<double>(sys.frame_stats().adjusted));

            // The changed list is complete: the buffer equals a full copy.
            if (std::memcmp(gpu.data(), records.data(), records.size() * sizeof(PlumageFeatherInstance)) != 0) {
                if (mismatched_frames++ == 0) first_mismatch = f;
            }
            if (opt.per_frame) {
                std::printf("  frame %3u: step %7.2f ms, listed %6zu (%5.1f %%), %5zu ranges, %9zu record bytes, adjusted %6.0f\n",
                            f, step_ms.back(), count, 100.0 * static_cast<double>(count) / static_cast<double>(n), made,
                            count * sizeof(PlumageFeatherInstance), adjusted.back());
            }
        }

        // Below 1 on this one thread: the loop waited for a core, its times are inflated.
        const double cpu_per_wall =
            static_cast<double>(std::clock() - cpu_loop) / CLOCKS_PER_SEC / std::max(seconds_since(t_loop), 1e-9);
        const double listed_mean = mean(listed);
        const double bytes_mean = mean(record_bytes);
        std::printf("  per frame over %u frames (60 fps; CPU / wall of the loop %.2f):\n", opt.frames, cpu_per_wall);
        std::printf("    step                     mean %.2f ms, p95 %.2f ms (readjusted %.0f feathers, %.1f %%)\n",
                    mean(step_ms), p95(step_ms), mean(adjusted), 100.0 * mean(adjusted) / static_cast<double>(n));
        std::printf("    records + changed list   %.0f feathers listed (%.1f %%), %.1f ranges, %.0f bytes uploaded; "
                    "pull and copy %.3f ms\n",
                    listed_mean, 100.0 * listed_mean / static_cast<double>(n), mean(ranges), bytes_mean, mean(pull_ms));
        std::printf("    every record             %zu bytes (36 a feather)\n", n * sizeof(PlumageFeatherInstance));
        std::printf("    full geometry            %zu bytes (positions + normals of %llu vertices); pull %.3f ms\n",
                    geometry_bytes, static_cast<unsigned long long>(geo.vertex_count), mean(geometry_ms));
        std::printf("    full geometry / records + changed list: %.1f\n", geometry_bytes / std::max(bytes_mean, 1.0));
        std::printf("RESULT preset=%s wave=%s feathers=%zu frames=%u step_ms_mean=%.3f step_ms_p95=%.3f listed_mean=%.1f "
                    "listed_percent=%.1f ranges_mean=%.1f record_bytes_mean=%.0f all_records_bytes=%zu geometry_bytes=%zu "
                    "ratio=%.2f pull_ms_mean=%.3f geometry_ms_mean=%.3f adjusted_mean=%.1f create_s=%.3f cpu_per_wall=%.2f\n",
                    preset, wave, n, opt.frames, mean(step_ms), p95(step_ms), listed_mean,
                    100.0 * listed_mean / static_cast<double>(n), mean(ranges), bytes_mean,
                    n * sizeof(PlumageFeatherInstance), geometry_bytes, geometry_bytes / std::max(bytes_mean, 1.0),
                    mean(pull_ms), mean(geometry_ms), mean(adjusted), create_s, cpu_per_wall);

        if (opt.validate) {
            const PlumageValidation v = sys.validate();
            std::printf("  validation after frame %u: %llu intersecting pairs, %llu body penetrations, coverage %.3f, "
                        "tip height median %.3f\n",
                        opt.frames, static_cast<unsigned long long>(v.intersecting_pairs),
                        static_cast<unsigned long long>(v.body_penetrations), v.coverage, v.tip_height_median);
        }
        if (!all_after_create || frames_all != 0 || mismatched_frames != 0) {
            std::fprintf(stderr,
                         "plumage_engine_example: FAILED: 'all' after create %d (want 1), steps listing all %zu (want 0), "
                         "frames whose buffer differs from a full copy %zu (first %u)\n",
                         all_after_create, frames_all, mismatched_frames, first_mismatch);
            return 1;
        }
        std::printf("  the buffer kept from the changed lists equals a full copy of the records after every frame\n");
        return 0;
    } catch (const plumage::Error& e) {
        std::fprintf(stderr, "plumage_engine_example: %s: %s\n", e.status_name(), e.message().c_str());
        return 4;
    }
}
