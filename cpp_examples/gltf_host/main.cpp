// plumage_gltf: dresses an animated glTF mesh (or the built-in model) with
// Plumage feathers frame by frame, and writes a report and a .glb.
#include "errors.h"
#include "gltf_loader.h"
#include "gltf_scene.h"
#include "gltf_writer.h"
#include "instance_writer.h"
#include "memory_usage.h"
#include "mesh_union.h"
#include "options.h"
#include "plumage_system.h"
#include "pose_writer.h"
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

// The vertex attributes the options name, read from the dressed mesh.
VertexMaps read_maps(const GltfScene& scene, const tinygltf::Model& model, const Options& opt) {
    const auto read = [&](const VertexMapSpec& m) {
        return m.attribute.empty() ? std::vector<float>{} : scene.vertex_attribute(model, m.attribute, m.first, 1);
    };
    const VertexMapSpec& flow = opt.flow_map;
    std::vector<float> directions = flow.attribute.empty() ? std::vector<float>{} : scene.rest_directions(model, flow.attribute, flow.first);
    VertexMaps maps{read(opt.spacing_map), read(opt.length_map), read(opt.width_map), std::move(directions), read(opt.layer_map), std::nullopt, {}, {}};
    // Types are whole numbers in the attribute (rounded; negative ones are 0).
    for (float t : read(opt.type_map)) maps.feather_type.push_back(static_cast<uint32_t>(std::lround(std::max(t, 0.0f))));
    return maps;
}

// The input mesh's material, with the UVs its base colour texture needs.
std::optional<BodyMaterial> mesh_material(const tinygltf::Model& model, const GltfScene& scene) {
    std::optional<BodyMaterial> material = input_material(model, scene.mesh_index());
    if (material && material->base_color_texture) {
        try {
            material->uvs = scene.vertex_attribute(model, "TEXCOORD_" + std::to_string(material->base_color_uv_set), 0, 2);
        } catch (const std::exception&) {
            material->uvs.clear();  // a primitive without them: the writer drops the texture
        }
    }
    return material;
}

// What the host dresses: one mesh, or several as one (a MeshUnion), with
// where each sits in what the library gets and its material.
struct Subject {
    std::unique_ptr<AnimatedMesh> mesh;
    std::vector<MeshPart> parts;                          // one per dressed mesh
    std::vector<std::optional<BodyMaterial>> materials;  // per part: the input's, if it had one
};

Subject open_subject(const Options& opt, VertexMaps& maps) {
    Subject s;
    if (!opt.input.empty()) {
        const tinygltf::Model model = load_gltf_file(opt.input);
        const std::vector<int> chosen = choose_meshes(model, opt.meshes);
        std::vector<std::unique_ptr<AnimatedMesh>> scenes;
        VertexMaps all;
        for (int m : chosen) {
            auto scene = std::make_unique<GltfScene>(model, m, opt.animation);
            VertexMaps part = read_maps(*scene, model, opt);
            for (auto [to, from] : {std::pair{&all.spacing, &part.spacing}, {&all.length, &part.length}, {&all.width, &part.width}, {&all.flow, &part.flow}, {&all.layer, &part.layer}}) {
                to->insert(to->end(), from->begin(), from->end());
            }
            all.feather_type.insert(all.feather_type.end(), part.feather_type.begin(), part.feather_type.end());
            s.materials.push_back(mesh_material(model, *scene));
            scenes.push_back(std::move(scene));
        }
        if (!opt.type_map.attribute.empty()) {
            all.feather_types = opt.feather_types.empty() ? std::vector<uint32_t>{PLUMAGE_PRESET_FEATHERS, PLUMAGE_PRESET_SCALES} : opt.feather_types;
        }
        maps = std::move(all);
        if (scenes.size() == 1) {
            s.parts.push_back(MeshPart{scenes[0]->mesh_name(), chosen[0], 0, scenes[0]->vertex_count(), 0, scenes[0]->triangle_count()});
            s.mesh = std::move(scenes[0]);
        } else {
            auto joined = std::make_unique<MeshUnion>(std::move(scenes), chosen);
            s.parts = joined->parts();
            s.mesh = std::move(joined);
        }
        return s;
    }
    const auto [rings, segments] = opt.model_resolution.value_or(std::array<uint32_t, 2>{ProceduralBody::kRings, ProceduralBody::kSegments});
    auto body = std::make_unique<ProceduralBody>(static_cast<int>(rings), static_cast<int>(segments));
    for (const std::string& m : opt.meshes) {
        if (m != body->mesh_name() && m != "0" && m != "all") throw UsageError("--mesh " + m + ": the built-in model has one mesh, procedural_body");
    }
    if (opt.meshes.size() > 1) throw UsageError("--mesh: the built-in model has one mesh, procedural_body; give --mesh once");
    if (!opt.animation.empty() && opt.animation != "swim" && opt.animation != "0") throw UsageError("--animation " + opt.animation + ": the built-in model has one clip, swim");
    s.parts.push_back(MeshPart{body->mesh_name(), 0, 0, body->vertex_count(), 0, body->triangle_count()});
    s.materials.emplace_back();
    s.mesh = std::move(body);
    return s;
}

PlumageConfig make_config(const Options& opt) {
    PlumageConfig cfg;
    plumage_config_init(&cfg);
    if (opt.preset) check(plumage_config_init_preset(&cfg, *opt.preset), nullptr, "plumage_config_init_preset");
    if (opt.feathers) cfg.target_feathers = *opt.feathers;
    if (opt.spacing) cfg.spacing = *opt.spacing;
    if (opt.sampler) cfg.sampler = *opt.sampler;
    if (opt.theta_deg) cfg.theta = static_cast<float>(*opt.theta_deg * kPi / 180.0);
    if (opt.seed) cfg.seed = *opt.seed;
    if (opt.flow) std::copy(opt.flow->begin(), opt.flow->end(), cfg.flow_axis);
    if (opt.flow_source) {
        cfg.flow_source_enabled = 1;
        std::copy(opt.flow_source->begin(), opt.flow_source->end(), cfg.flow_source);
    }
    if (opt.mode) cfg.mode = *opt.mode;
    if (opt.drift_tolerance_deg) cfg.drift_tolerance = static_cast<float>(*opt.drift_tolerance_deg * kPi / 180.0);
    if (opt.settle_rate_deg) cfg.settle_rate = static_cast<float>(*opt.settle_rate_deg * kPi / 180.0);
    if (opt.curvature_min_scale) cfg.curvature_min_scale = *opt.curvature_min_scale;
    if (opt.shaft_segments) cfg.shaft_segments = *opt.shaft_segments;
    if (opt.bend_limit_deg) cfg.bend_limit = static_cast<float>(*opt.bend_limit_deg * kPi / 180.0);
    if (opt.fluffiness_deg) cfg.fluffiness = static_cast<float>(*opt.fluffiness_deg * kPi / 180.0);
    if (opt.threads) cfg.threads = *opt.threads;
    if (opt.memory_limit_mib) cfg.memory_limit = *opt.memory_limit_mib << 20;
    return cfg;
}

// Clip times of the frames to step: the clip's start + --start + k / fps,
// up to the end of the clip by default.
std::vector<double> frame_times(const Options& opt, const std::optional<ClipInfo>& clip) {
    if (clip && opt.start > clip->duration + 1e-9) {
        char message[256];
        std::snprintf(message, sizeof message, "--start %g is past the end of clip \"%s\" (%g s long)", opt.start, clip->name.c_str(), clip->duration);
        throw UsageError(message);
    }
    size_t n = 0;
    if (opt.frames) n = static_cast<size_t>(*opt.frames);
    else if (clip) n = static_cast<size_t>(std::floor((clip->duration - opt.start) * opt.fps + 1e-6)) + 1;
    std::vector<double> times(n);
    const double first = (clip ? clip->start : 0.0) + opt.start;
    for (size_t k = 0; k < n; ++k) times[k] = first + static_cast<double>(k) / opt.fps;
    return times;
}

nlohmann::ordered_json run_config(const PlumageConfig& cfg, const Options& opt, const std::optional<ClipInfo>& clip, size_t frames, const VertexMaps& vertex_maps) {
    nlohmann::ordered_json j = config_to_json(cfg);
    // Where the orientation field comes from (the library's precedence).
    j["flow_from"] = !vertex_maps.flow.empty() ? "flow_map" : cfg.flow_source_enabled ? "flow_source" : vertex_maps.skeleton ? "skeleton" : "flow_axis";
    if (vertex_maps.skeleton) j["skeleton_joints"] = vertex_maps.skeleton->joint_count();
    j["fps"] = opt.fps;
    j["start"] = opt.start;
    j["frames"] = frames;
    j["animation"] = clip ? nlohmann::ordered_json{{"name", clip->name}, {"index", clip->index}, {"start", clip->start}, {"duration", clip->duration}}
                          : nlohmann::ordered_json(nullptr);
    const std::pair<const char*, const VertexMapSpec*> maps[] = {{"spacing_map", &opt.spacing_map}, {"length_map", &opt.length_map}, {"width_map", &opt.width_map}, {"flow_map", &opt.flow_map}, {"layer_map", &opt.layer_map}, {"type_map", &opt.type_map}};
    for (const auto& [key, m] : maps) {
        if (!m->attribute.empty()) j[key] = m->attribute + ":" + std::to_string(m->first);
    }
    j["validate"] = validate_name(opt.validate);
    j["plumage_version"] = plumage_version();
    return j;
}

// With no flow given (--flow, --flow-source or --flow-map), a skinned
// subject's feathers follow its skeleton (the library walks the bones from
// the head); any other's flow from the front of the model to its back: the
// source is the rest vertex farthest along the way the model faces (+Z for
// glTF; the lowest index among equals), and the library's flow away from
// it along the surface runs down the body, the limbs and the tail.
void default_flow(const Options& opt, const AnimatedMesh& subject, PlumageConfig& cfg, VertexMaps& maps) {
    const std::vector<float>& rest = subject.rest_positions();
    if (opt.flow || opt.flow_source || !opt.flow_map.attribute.empty() || rest.empty()) return;
    if (opt.skeleton_flow) maps.skeleton = subject.skeleton();
    if (maps.skeleton) return;
    const std::array<float, 3> f = subject.facing();
    const auto ahead = [&](size_t v) { return rest[3 * v] * f[0] + rest[3 * v + 1] * f[1] + rest[3 * v + 2] * f[2]; };
    size_t front = 0;
    for (size_t v = 1; v < rest.size() / 3; ++v) {
        if (ahead(v) > ahead(front)) front = v;
    }
    cfg.flow_source_enabled = 1;
    std::copy(rest.begin() + static_cast<std::ptrdiff_t>(3 * front), rest.begin() + static_cast<std::ptrdiff_t>(3 * front + 3), cfg.flow_source);
}

bool validate_frame(ValidateWhen when, size_t k, size_t n) { return when == ValidateWhen::Every || (when == ValidateWhen::Last && k + 1 == n); }

// One run of the host: the rest pose, then every frame, then the outputs.
class Session {
public:
    explicit Session(const Options& opt) : opt_(opt) {
        const Stopwatch load_clock;
        Subject subject = open_subject(opt_, maps_);
        subject_ = std::move(subject.mesh);
        parts_ = std::move(subject.parts);
        materials_ = std::move(subject.materials);
        report_.set_timing("load_seconds", load_clock.seconds());
        report_.set_memory("after_load", memory_usage());
        clip_ = subject_->clip();
        times_ = frame_times(opt_, clip_);
    }

    void create_rest_pose() {
        PlumageConfig cfg = make_config(opt_);
        default_flow(opt_, *subject_, cfg, maps_);
        cfg.progress = &ProgressLine::library_callback;
        cfg.progress_user_data = &progress_;
        report_.set_subject(opt_.input.empty() ? "builtin:procedural_body" : opt_.input, subject_->mesh_name(), subject_->vertex_count(),
                            subject_->triangle_count(), run_config(cfg, opt_, clip_, times_.size(), maps_));
        progress_.set_context("rest pose");
        const Stopwatch create_clock;
        sys_ = create_system(cfg, subject_->rest_positions(), subject_->triangles(), maps_);
        report_.set_timing("create_seconds", create_clock.seconds());
        report_.set_memory("after_create", memory_usage(sys_.get()));
        check(plumage_system_feather_count(sys_.get(), &feather_count_), sys_.get(), "plumage_system_feather_count");
        report_.set_feathers(feather_count_);
        report_.set_sampling(sampling_stats(*sys_));
        report_.set_ordering(ordering_stats(*sys_));
        report_.set_static(frame_stats(*sys_), opt_.validate != ValidateWhen::None ? validate(*sys_) : std::nullopt);
        if (several()) {
            report_.set_parts(parts_);
            for (size_t p = 0; p < parts_.size(); ++p) {
                const MeshPart& part = parts_[p];
                report_.set_part_static(p, part_stats(*sys_, part.first_triangle, part.triangle_count),
                                        opt_.validate != ValidateWhen::None ? validate_part(*sys_, part.first_triangle, part.triangle_count) : std::nullopt);
            }
        }
        if (!opt_.poses.empty()) {
            poses_ = std::make_unique<PoseWriter>(opt_.poses, cfg, opt_.fps, subject_->rest_positions(), subject_->triangles(), times_, maps_);
        }
        if (!opt_.instances.empty()) {
            instances_.emplace(opt_.instances, *sys_, subject_->rest_positions(), subject_->triangles());
            instances_->add_frame(*sys_, -1.0, subject_->rest_positions(), true);
        }
        if (!opt_.out.empty()) {
            recorder_.emplace(subject_->rest_positions(), subject_->triangles(), feathers(*sys_), feather_mesh(*sys_));
            if (several()) {
                std::vector<BodyMaterial> materials;
                for (const auto& m : materials_) materials.push_back(m.value_or(BodyMaterial{}));
                recorder_->set_parts(parts_, std::move(materials));
            } else if (materials_.front()) {
                recorder_->set_body_material(*materials_.front());
            }
        }
    }

    void step_frames() {
        const Stopwatch frames_clock;
        std::vector<float> pose;
        for (size_t k = 0; k < times_.size(); ++k) {
            subject_->pose_at(times_[k], pose);
            progress_.set_context("frame " + std::to_string(k + 1) + "/" + std::to_string(times_.size()));
            const Stopwatch step_clock;
            check(plumage_system_step(sys_.get(), pose.data(), pose.size() / 3), sys_.get(), "plumage_system_step");
            const double step_seconds = step_clock.seconds();
            step_total_ += step_seconds;
            // Validation and copies happen after the clock stopped: not step time.
            const std::optional<PlumageValidation> v = validate_frame(opt_.validate, k, times_.size()) ? validate(*sys_) : std::nullopt;
            if (recorder_) recorder_->add_frame(times_[k], pose, feathers(*sys_), feather_mesh(*sys_));
            if (poses_) poses_->add_frame(pose);
            if (instances_) instances_->add_frame(*sys_, times_[k], pose, k + 1 == times_.size());
            report_.add_frame(k, times_[k], step_seconds, frame_stats(*sys_), v, memory_usage(sys_.get()));
            for (size_t p = 0; several() && p < parts_.size(); ++p) {
                const MeshPart& part = parts_[p];
                const bool check = validate_frame(opt_.validate, k, times_.size());
                report_.add_part_frame(p, k, part_stats(*sys_, part.first_triangle, part.triangle_count),
                                       check ? validate_part(*sys_, part.first_triangle, part.triangle_count) : std::nullopt);
            }
            progress_.frame_done(k + 1, times_.size(), step_seconds);
        }
        progress_.clear();
        report_.set_timing("frames_seconds", frames_clock.seconds());
    }

    void finish() {
        std::printf("plumage_gltf: %s, mesh \"%s\": %zu vertices, %zu triangles, %zu feathers\n", opt_.input.empty() ? "built-in model" : opt_.input.c_str(),
                    subject_->mesh_name().c_str(), subject_->vertex_count(), subject_->triangle_count(), feather_count_);
        for (size_t p = 0; several() && p < parts_.size(); ++p) {
            const MeshPart& part = parts_[p];
            std::printf("plumage_gltf:   mesh %d \"%s\": %zu vertices, %zu triangles, %llu feathers\n", part.index, part.name.c_str(), part.vertex_count,
                        part.triangle_count, static_cast<unsigned long long>(part_stats(*sys_, part.first_triangle, part.triangle_count).feathers));
        }
        if (!times_.empty()) {
            std::printf("plumage_gltf: %zu frames of \"%s\" at %g fps, mean step %.3f ms\n", times_.size(), clip_ ? clip_->name.c_str() : "(no clip)",
                        opt_.fps, step_total_ / static_cast<double>(times_.size()) * 1e3);
        }
        if (recorder_) {
            const Stopwatch write_clock;
            recorder_->write_glb(opt_.out);
            report_.set_timing("write_seconds", write_clock.seconds());
            std::printf("plumage_gltf: wrote %s\n", opt_.out.c_str());
            if (recorder_->untracked_feathers() > 0) {
                std::printf("plumage_gltf: %zu feathers absent at rest were left out of the .glb\n", recorder_->untracked_feathers());
            }
        }
        if (poses_) {
            poses_->finish();
            std::printf("plumage_gltf: wrote %s\n", opt_.poses.c_str());
        }
        if (instances_) {
            instances_->finish();
            std::printf("plumage_gltf: wrote %s\n", instances_->dir().c_str());
        }
        if (!opt_.report.empty()) {
            report_.set_timing("total_seconds", total_.seconds());
            report_.write(opt_.report);
            std::printf("plumage_gltf: wrote %s\n", opt_.report.c_str());
        }
    }

private:
    bool several() const { return parts_.size() > 1; }

    const Options& opt_;
    Stopwatch total_;
    std::unique_ptr<AnimatedMesh> subject_;
    VertexMaps maps_;
    std::vector<MeshPart> parts_;                          // the dressed meshes, one or more
    std::vector<std::optional<BodyMaterial>> materials_;  // per part: the input mesh's, if it had one
    std::optional<ClipInfo> clip_;
    std::vector<double> times_;
    Report report_;
    ProgressLine progress_;  // the library holds a pointer to it: declared before, so destroyed after, the system
    SystemHandle sys_;
    size_t feather_count_ = 0;
    std::optional<AnimationRecorder> recorder_;
    std::unique_ptr<PoseWriter> poses_;
    std::optional<InstanceWriter> instances_;
    double step_total_ = 0;
};

int run(int argc, const char* const* argv) {
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
    Session session(opt);
    session.create_rest_pose();
    session.step_frames();
    session.finish();
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
