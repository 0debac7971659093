#include "report.h"

#include "errors.h"
#include "options.h"
#include "plumage_system.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>

namespace plumage_host {
namespace {

using json = nlohmann::ordered_json;

// JSON has no NaN or infinity: such a figure is left out.
void put(json& j, const char* key, double v) {
    if (std::isfinite(v)) j[key] = v;
}

// The validation figures, shared by `static` and each frame.
void put_validation(json& j, const PlumageValidation& v) {
    if (PLUMAGE_FILLED(v, intersecting_pairs)) j["intersecting_pairs"] = v.intersecting_pairs;
    if (PLUMAGE_FILLED(v, body_penetrations)) j["body_penetrations"] = v.body_penetrations;
    if (PLUMAGE_FILLED(v, coverage)) put(j, "coverage", v.coverage);
    if (PLUMAGE_FILLED(v, mean_pitch_deg)) put(j, "mean_pitch_deg", v.mean_pitch_deg);
    if (PLUMAGE_FILLED(v, probes)) j["coverage_probes"] = v.probes;
    if (PLUMAGE_FILLED(v, buried_probes)) j["buried_probes"] = v.buried_probes;
    if (PLUMAGE_FILLED(v, tip_height_median)) put(j, "tip_height_median", v.tip_height_median);
    if (PLUMAGE_FILLED(v, tip_height_p90)) put(j, "tip_height_p90", v.tip_height_p90);
    if (PLUMAGE_FILLED(v, bristle_percent)) put(j, "bristle_percent", v.bristle_percent);
    if (PLUMAGE_FILLED(v, stack_efficiency)) put(j, "stack_efficiency", v.stack_efficiency);
    if (PLUMAGE_FILLED(v, stack_depth_median)) put(j, "stack_depth_median", v.stack_depth_median);
    if (PLUMAGE_FILLED(v, discord_percent)) put(j, "discord_percent", v.discord_percent);
}

// The adjustment's figures, shared by `static` and each frame.
void put_adjustment(json& j, const PlumageFrameStats& s) {
    if (PLUMAGE_FILLED(s, collision_tests_per_feather)) put(j, "collision_tests_per_feather", s.collision_tests_per_feather);
    if (PLUMAGE_FILLED(s, clamped)) j["clamped"] = s.clamped;
    if (PLUMAGE_FILLED(s, drape_descents)) {
        j["draped"] = s.draped;
        j["drape_descents"] = s.drape_descents;
    }
    if (PLUMAGE_FILLED(s, kept_in_place)) j["kept_in_place"] = s.kept_in_place;
    if (PLUMAGE_FILLED(s, levels)) j["levels"] = s.levels;
    if (PLUMAGE_FILLED(s, neighbourhood_seconds)) put(j, "neighbourhood_seconds", s.neighbourhood_seconds);
}

// The memory figures, shared by `memory` and each frame.
void put_memory(json& j, const MemoryUsage& m) {
    if (m.rss_kib) j["rss_kib"] = *m.rss_kib;
    if (m.peak_rss_kib) j["peak_rss_kib"] = *m.peak_rss_kib;
    if (m.heap_kib) j["heap_kib"] = *m.heap_kib;
    if (m.system) {
        const PlumageMemory& s = *m.system;
        j["system_bytes"] = {{"total", s.total},   {"mesh", s.mesh},       {"coat", s.coat}, {"neighbourhoods", s.neighbourhoods},
                             {"history", s.history}, {"scratch", s.scratch}};
    }
}

// Mean (how 0), max (how > 0) or min (how < 0) of `key` over the frames that have it.
std::optional<double> fold(const json& frames, const char* key, int how) {
    std::optional<double> acc;
    size_t n = 0;
    for (const json& f : frames) {
        if (!f.contains(key)) continue;
        const double v = f[key].get<double>();
        ++n;
        if (!acc) acc = v;
        else if (how == 0) *acc += v;
        else if (how > 0) *acc = std::max(*acc, v);
        else *acc = std::min(*acc, v);
    }
    if (acc && how == 0) *acc /= static_cast<double>(n);
    return acc;
}

// The summary of `frames`: the step's work and times (`whole`: the run's
// frames, not one mesh's), then the coat's quality at its worst.
json summarise(const json& frames, bool whole) {
    json s = {{"frames", frames.size()}};
    const auto add = [&](const char* key, const char* field, int how) {
        const std::optional<double> v = fold(frames, field, how);
        if (!v) return;
        if (how == 1) s[key] = static_cast<uint64_t>(*v);  // a maximum of counts is a count
        else s[key] = *v;
    };
    add("mean_adjusted", "adjusted", 0);
    if (whole) {
        add("mean_verified", "verified", 0);
        add("mean_step_seconds", "step_seconds", 0);
        add("mean_library_step_seconds", "library_step_seconds", 0);
        add("mean_neighbourhood_seconds", "neighbourhood_seconds", 0);
        add("mean_levels", "levels", 0);
    }
    add("max_intersecting_pairs", "intersecting_pairs", 1);
    add("max_body_penetrations", "body_penetrations", 1);
    add("min_coverage", "coverage", -1);
    add("max_tip_height_median", "tip_height_median", 2);
    add("max_tip_height_p90", "tip_height_p90", 2);
    add("max_bristle_percent", "bristle_percent", 2);
    add("max_stack_efficiency", "stack_efficiency", 2);
    add("max_discord_percent", "discord_percent", 2);
    add("mean_pops_percent", "pops_percent", 0);
    add("max_pops_percent", "pops_percent", 2);
    return s;
}

}  // namespace

double tidy(float v) {
    if (!std::isfinite(v)) return v;
    for (int digits = 6; digits <= 9; ++digits) {
        char text[32];
        std::snprintf(text, sizeof text, "%.*g", digits, static_cast<double>(v));
        const double d = std::strtod(text, nullptr);
        if (static_cast<float>(d) == v) return d;
    }
    return v;
}

json config_to_json(const PlumageConfig& c) {
    json j = {{"sampler", sampler_name(c.sampler)},
              {"seed", c.seed},
              {"threads", c.threads},
              {"mode", mode_name(c.mode)},
              {"target_feathers", c.target_feathers},
              {"k_neighbours", c.k_neighbours},
              {"spacing", tidy(c.spacing)},
              {"theta_deg", tidy(static_cast<float>(c.theta * 180.0 / 3.14159265358979323846))},
              {"randomness", tidy(c.randomness)},
              {"pool_factor", tidy(c.pool_factor)},
              {"feather_length", tidy(c.feather_length)},
              {"feather_width", tidy(c.feather_width)},
              {"feather_thickness", tidy(c.feather_thickness)},
              {"gamma", tidy(c.gamma)},
              {"lambda", tidy(c.lambda)},
              {"height_field_u", c.height_field_u},
              {"height_field_v", c.height_field_v},
              {"fluffiness", tidy(c.fluffiness)},
              {"collision_allowance", tidy(c.collision_allowance)},
              {"theta_s", tidy(c.theta_s)},
              {"drift_tolerance", tidy(c.drift_tolerance)},
              {"settle_rate", tidy(c.settle_rate)},
              {"curvature_min_scale", tidy(c.curvature_min_scale)},
              {"shaft_segments", c.shaft_segments},
              {"bend_limit", tidy(c.bend_limit)},
              {"length_per_spacing", tidy(c.length_per_spacing)},
              {"width_per_spacing", tidy(c.width_per_spacing)},
              {"flow_axis", {tidy(c.flow_axis[0]), tidy(c.flow_axis[1]), tidy(c.flow_axis[2])}},
              {"recompute_neighbourhoods", c.recompute_neighbourhoods != 0}};
    if (c.flow_source_enabled != 0)
        j["flow_source"] = {tidy(c.flow_source[0]), tidy(c.flow_source[1]), tidy(c.flow_source[2])};
    return j;
}

void Report::set_subject(const std::string& input, const std::string& mesh, size_t vertices, size_t triangles, json config) {
    subject_ = {{"input", input}, {"mesh", mesh}, {"vertices", vertices}, {"triangles", triangles}, {"config", std::move(config)}};
}

void Report::set_sampling(const std::optional<PlumageSamplingStats>& s) {
    if (!s) return;
    sampling_ = json::object();
    if (PLUMAGE_FILLED(*s, seconds)) put(sampling_, "seconds", s->seconds);
    if (PLUMAGE_FILLED(*s, relative_radius)) put(sampling_, "relative_radius", tidy(s->relative_radius));
    if (PLUMAGE_FILLED(*s, coverage_gap)) put(sampling_, "coverage_gap", tidy(s->coverage_gap));
    if (PLUMAGE_FILLED(*s, alignment)) put(sampling_, "alignment", tidy(s->alignment));
    if (PLUMAGE_FILLED(*s, field_singularities)) sampling_["field_singularities"] = s->field_singularities;
}

void Report::set_ordering(const std::optional<PlumageOrderingStats>& s) {
    if (!s) return;
    ordering_ = json::object();
    if (PLUMAGE_FILLED(*s, seconds)) put(ordering_, "seconds", s->seconds);
    if (PLUMAGE_FILLED(*s, pairs)) ordering_["pairs"] = s->pairs;
    if (PLUMAGE_FILLED(*s, edges)) ordering_["edges"] = s->edges;
    if (PLUMAGE_FILLED(*s, dropped_edges)) ordering_["dropped_edges"] = s->dropped_edges;
    if (PLUMAGE_FILLED(*s, violations)) ordering_["violations"] = s->violations;
}

void Report::set_static(const std::optional<PlumageFrameStats>& s, const std::optional<PlumageValidation>& v) {
    if (!s && !v) return;
    static_ = json::object();
    if (s) {
        if (PLUMAGE_FILLED(*s, adjust_seconds)) put(static_, "seconds", s->adjust_seconds);
        put_adjustment(static_, *s);
    }
    if (v) put_validation(static_, *v);
}

void Report::add_frame(size_t index, double time, double step_seconds, const std::optional<PlumageFrameStats>& s,
                       const std::optional<PlumageValidation>& v, const MemoryUsage& memory) {
    json f = {{"index", index}};
    put(f, "time", time);
    if (s) {
        if (PLUMAGE_FILLED(*s, adjusted)) f["adjusted"] = s->adjusted;
        if (PLUMAGE_FILLED(*s, verified)) f["verified"] = s->verified;
        if (PLUMAGE_FILLED(*s, deformed)) f["deformed"] = s->deformed;
        if (PLUMAGE_FILLED(*s, seeds)) f["seeds"] = s->seeds;
        put_adjustment(f, *s);
        if (PLUMAGE_FILLED(*s, pops)) {
            f["pops"] = s->pops;
            if (feathers_ > 0) put(f, "pops_percent", 100.0 * static_cast<double>(s->pops) / static_cast<double>(feathers_));
        }
        if (PLUMAGE_FILLED(*s, largest_pose_change_deg)) put(f, "largest_pose_change_deg", s->largest_pose_change_deg);
        if (PLUMAGE_FILLED(*s, priority_changes)) f["priority_changes"] = s->priority_changes;
        if (PLUMAGE_FILLED(*s, priority_change_percent)) put(f, "priority_change_percent", s->priority_change_percent);
        if (PLUMAGE_FILLED(*s, reversals)) f["reversals"] = s->reversals;
        if (PLUMAGE_FILLED(*s, reversals_refused)) f["reversals_refused"] = s->reversals_refused;
        if (PLUMAGE_FILLED(*s, cycles_broken)) f["cycles_broken"] = s->cycles_broken;
        if (PLUMAGE_FILLED(*s, reorder_seconds)) put(f, "reorder_seconds", s->reorder_seconds);
        if (PLUMAGE_FILLED(*s, adjust_seconds)) put(f, "adjust_seconds", s->adjust_seconds);
        if (PLUMAGE_FILLED(*s, step_seconds)) put(f, "library_step_seconds", s->step_seconds);
    }
    put(f, "step_seconds", step_seconds);
    if (v) put_validation(f, *v);
    put_memory(f, memory);
    frames_.push_back(std::move(f));
}

void Report::set_memory(const std::string& phase, const MemoryUsage& m) {
    json j = json::object();
    put_memory(j, m);
    if (!j.empty()) memory_[phase] = std::move(j);
}

void Report::set_parts(const std::vector<MeshPart>& parts) {
    parts_.clear();
    for (const MeshPart& p : parts) {
        parts_.push_back(Part{{{"name", p.name},
                               {"index", p.index},
                               {"vertices", p.vertex_count},
                               {"triangles", p.triangle_count},
                               {"first_triangle", p.first_triangle}},
                              0,
                              nullptr,
                              json::array()});
    }
}

namespace {

// A mesh's share of a frame's adjustment: adjusted, pops and the largest change.
void put_part_stats(json& j, const PlumagePartStats& s, uint64_t feathers) {
    if (PLUMAGE_FILLED(s, adjusted)) j["adjusted"] = s.adjusted;
    if (PLUMAGE_FILLED(s, pops)) {
        j["pops"] = s.pops;
        if (feathers > 0) put(j, "pops_percent", 100.0 * static_cast<double>(s.pops) / static_cast<double>(feathers));
    }
    if (PLUMAGE_FILLED(s, largest_pose_change_deg)) put(j, "largest_pose_change_deg", s.largest_pose_change_deg);
}

}  // namespace

void Report::set_part_static(size_t part, const PlumagePartStats& s, const std::optional<PlumageValidation>& v) {
    Part& p = parts_.at(part);
    if (PLUMAGE_FILLED(s, feathers)) p.feathers = s.feathers;
    p.subject["feathers"] = p.feathers;
    if (PLUMAGE_FILLED(s, placed)) p.subject["placed"] = s.placed;
    p.static_figures = json::object();
    if (v) put_validation(p.static_figures, *v);
    if (p.static_figures.empty()) p.static_figures = nullptr;
}

void Report::add_part_frame(size_t part, size_t index, const PlumagePartStats& s, const std::optional<PlumageValidation>& v) {
    Part& p = parts_.at(part);
    json f = {{"index", index}};
    put_part_stats(f, s, p.feathers);
    if (v) put_validation(f, *v);
    p.frames.push_back(std::move(f));
}

json Report::part_json(size_t part) const {
    const Part& p = parts_.at(part);
    json j = p.subject;
    if (!p.static_figures.is_null()) j["static"] = p.static_figures;
    j["frames"] = p.frames;
    j["summary"] = summarise(p.frames, false);
    return j;
}

json Report::summary() const { return summarise(frames_, true); }

json Report::to_json() const {
    json j = {{"schema", 1}};
    for (const char* key : {"input", "mesh", "vertices", "triangles"}) j[key] = subject_[key];
    j["feathers"] = feathers_;
    j["config"] = subject_["config"];
    if (!sampling_.is_null()) j["sampling"] = sampling_;
    if (!ordering_.is_null()) j["ordering"] = ordering_;
    if (!static_.is_null()) j["static"] = static_;
    if (!parts_.empty()) {
        j["meshes"] = json::array();
        for (size_t p = 0; p < parts_.size(); ++p) j["meshes"].push_back(part_json(p));
    }
    if (!memory_.empty()) j["memory"] = memory_;
    j["frames"] = frames_;
    j["summary"] = summary();
    j["timing"] = timing_;
    return j;
}

void Report::write(const std::string& path) const {
    std::error_code ec;
    const std::filesystem::path parent = std::filesystem::path(path).parent_path();
    if (!parent.empty()) std::filesystem::create_directories(parent, ec);
    std::ofstream out(path);
    out << to_json().dump(2) << '\n';
    out.close();
    if (!out) throw OutputError("cannot write " + path);
}

}  // namespace plumage_host
