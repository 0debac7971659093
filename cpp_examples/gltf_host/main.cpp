// plumage_gltf: dresses an animated glTF mesh (or the built-in model) with
// Plumage feathers frame by frame, and writes a report and a .glb.
#include "errors.h"
#include "gltf_loader.h"
#include "gltf_scene.h"
#include "gltf_writer.h"
#include "options.h"
#include "plumage_system.h"
#include "procedural_model.h"
#include "progress.h"
#include "report.h"

#include <cmath>
#include <cstdio>
#include <iostream>
#include <memory>
#include <new>

namespace plumage_host {
namespace {

constexpr double kPi = 3.14159265358979323846;

std::unique_ptr<AnimatedMesh> open_subject(const Options& opt) {
    if (!opt.input.empty()) return std::make_unique<GltfScene>(load_gltf_file(opt.input), opt.mesh, opt.animation);
    auto body = std::make_unique<ProceduralBody>();
    if (!opt.mesh.empty() && opt.mesh != body->mesh_name() && opt.mesh != "0") throw UsageError("--mesh " + opt.mesh + ": the built-in model has one mesh, procedural_body");
    if (!opt.animation.empty() && opt.animation != "swim" && opt.animation != "0") throw UsageError("--animation " + opt.animation + ": the built-in model has one clip, swim");
    return body;
}

PlumageConfig make_config(const Options& opt) {
    PlumageConfig cfg;
    plumage_config_init(&cfg);
    if (opt.feathers) cfg.target_feathers = *opt.feathers;
    if (opt.spacing) cfg.spacing = *opt.spacing;
    if (opt.sampler) cfg.sampler = *opt.sampler;
    if (opt.theta_deg) cfg.theta = static_cast<float>(*opt.theta_deg * kPi / 180.0);
    if (opt.seed) cfg.seed = *opt.seed;
    if (opt.flow) std::copy(opt.flow->begin(), opt.flow->end(), cfg.flow_axis);
    if (opt.mode) cfg.mode = *opt.mode;
    if (opt.threads) cfg.threads = *opt.threads;
    return cfg;
}

// Clip times of the frames to step: start + k / fps, the whole clip by default.
std::vector<double> frame_times(const Options& opt, const std::optional<ClipInfo>& clip) {
    size_t n = 0;
    if (opt.frames) n = static_cast<size_t>(*opt.frames);
    else if (clip) n = static_cast<size_t>(std::floor(clip->duration * opt.fps + 1e-6)) + 1;
    std::vector<double> times(n);
    for (size_t k = 0; k < n; ++k) times[k] = (clip ? clip->start : 0.0) + static_cast<double>(k) / opt.fps;
    return times;
}

nlohmann::ordered_json run_config(const PlumageConfig& cfg, const Options& opt, const std::optional<ClipInfo>& clip, size_t frames) {
    nlohmann::ordered_json j = config_to_json(cfg);
    j["fps"] = opt.fps;
    j["frames"] = frames;
    j["animation"] = clip ? nlohmann::ordered_json{{"name", clip->name}, {"index", clip->index}, {"start", clip->start}, {"duration", clip->duration}}
                          : nlohmann::ordered_json(nullptr);
    j["validate"] = validate_name(opt.validate);
    j["plumage_version"] = plumage_version();
    return j;
}

bool validate_frame(ValidateWhen when, size_t k, size_t n) { return when == ValidateWhen::Every || (when == ValidateWhen::Last && k + 1 == n); }

int run(int argc, const char* const* argv) {
    const Stopwatch total;
    const Options opt = parse_options(argc, argv);
    if (opt.help) {
        std::cout << usage_text();
        return 0;
    }
    if (opt.version) {
        std::cout << "plumage_gltf (Plumage " << plumage_version() << ", ABI " << plumage_abi_version() << ")\n";
        return 0;
    }
    check_abi();

    const Stopwatch load_clock;
    const std::unique_ptr<AnimatedMesh> subject = open_subject(opt);
    const double load_seconds = load_clock.seconds();
    const std::optional<ClipInfo> clip = subject->clip();
    const std::vector<double> times = frame_times(opt, clip);
    ProgressLine progress;
    PlumageConfig cfg = make_config(opt);
    cfg.progress = &ProgressLine::library_callback;
    cfg.progress_user_data = &progress;

    Report report;
    report.set_subject(opt.input.empty() ? "builtin:procedural_body" : opt.input, subject->mesh_name(), subject->vertex_count(),
                       subject->triangle_count(), run_config(cfg, opt, clip, times.size()));
    report.set_timing("load_seconds", load_seconds);

    progress.set_context("rest pose");
    const Stopwatch create_clock;
    const SystemHandle sys = create_system(cfg, subject->rest_positions(), subject->triangles());
    report.set_timing("create_seconds", create_clock.seconds());
    size_t feather_count = 0;
    check(plumage_system_feather_count(sys.get(), &feather_count), sys.get(), "plumage_system_feather_count");
    report.set_feathers(feather_count);
    report.set_sampling(sampling_stats(*sys));
    report.set_ordering(ordering_stats(*sys));
    report.set_static(frame_stats(*sys), opt.validate != ValidateWhen::None ? validate(*sys) : std::nullopt);

    std::optional<AnimationRecorder> recorder;
    if (!opt.out.empty()) recorder.emplace(subject->rest_positions(), subject->triangles(), feathers(*sys), feather_triangles(*sys));

    const Stopwatch frames_clock;
    std::vector<float> pose;
    double step_total = 0;
    for (size_t k = 0; k < times.size(); ++k) {
        subject->pose_at(times[k], pose);
        progress.set_context("frame " + std::to_string(k + 1) + "/" + std::to_string(times.size()));
        const Stopwatch step_clock;
        check(plumage_system_step(sys.get(), pose.data(), pose.size() / 3), sys.get(), "plumage_system_step");
        const double step_seconds = step_clock.seconds();
        step_total += step_seconds;
        const std::optional<PlumageValidation> v = validate_frame(opt.validate, k, times.size()) ? validate(*sys) : std::nullopt;
        report.add_frame(k, times[k], step_seconds, frame_stats(*sys), v);
        if (recorder) recorder->add_frame(times[k], pose, feathers(*sys), feather_triangles(*sys));
        progress.frame_done(k + 1, times.size(), step_seconds);
    }
    progress.clear();
    report.set_timing("frames_seconds", frames_clock.seconds());

    std::printf("plumage_gltf: %s, mesh \"%s\": %zu vertices, %zu triangles, %zu feathers\n", opt.input.empty() ? "built-in model" : opt.input.c_str(),
                subject->mesh_name().c_str(), subject->vertex_count(), subject->triangle_count(), feather_count);
    if (!times.empty()) {
        std::printf("plumage_gltf: %zu frames of \"%s\" at %g fps, mean step %.3f ms\n", times.size(), clip ? clip->name.c_str() : "(no clip)", opt.fps,
                    step_total / static_cast<double>(times.size()) * 1e3);
    }
    if (recorder) {
        const Stopwatch write_clock;
        recorder->write_glb(opt.out);
        report.set_timing("write_seconds", write_clock.seconds());
        std::printf("plumage_gltf: wrote %s\n", opt.out.c_str());
        if (recorder->untracked_feathers() > 0) std::printf("plumage_gltf: %zu feathers absent at rest were left out of the .glb\n", recorder->untracked_feathers());
    }
    if (!opt.report.empty()) {
        report.set_timing("total_seconds", total.seconds());
        report.write(opt.report);
        std::printf("plumage_gltf: wrote %s\n", opt.report.c_str());
    }
    return 0;
}

int fail(int code, const std::string& message) {
    std::fprintf(stderr, "plumage_gltf: %s\n", message.c_str());
    return code;
}

}  // namespace
}  // namespace plumage_host

int main(int argc, char** argv) {
    using namespace plumage_host;
    try {
        return run(argc, argv);
    } catch (const UsageError& e) {
        return fail(2, std::string(e.what()) + " (see --help)");
    } catch (const InputError& e) {
        return fail(3, e.what());
    } catch (const LibraryError& e) {
        return fail(4, e.what());
    } catch (const OutputError& e) {
        return fail(1, e.what());
    } catch (const std::bad_alloc&) {
        return fail(1, "out of memory");
    } catch (const std::exception& e) {
        return fail(1, std::string("internal error: ") + e.what());
    }
}
