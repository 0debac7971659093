// The machine-readable report (schema 1). Figures the library has not
// computed (its queries answer NOT_AVAILABLE) are left out, never invented.
#pragma once

#include "memory_usage.h"
#include "mesh_union.h"
#include "plumage.h"

#include <nlohmann/json.hpp>

#include <optional>
#include <string>
#include <vector>

namespace plumage_host {

class Report {
public:
    // What was dressed and how: `config` holds everything that shaped the run.
    void set_subject(const std::string& input, const std::string& mesh, size_t vertices, size_t triangles, nlohmann::ordered_json config);
    void set_feathers(size_t count) { feathers_ = count; }
    void set_sampling(const std::optional<PlumageSamplingStats>& s);
    void set_ordering(const std::optional<PlumageOrderingStats>& s);
    // The rest pose right after create: its adjustment and validation.
    void set_static(const std::optional<PlumageFrameStats>& s, const std::optional<PlumageValidation>& v);
    // One stepped frame; step_seconds is the wall time of plumage_system_step,
    // `memory` the process's memory right after it.
    void add_frame(size_t index, double time, double step_seconds, const std::optional<PlumageFrameStats>& s,
                   const std::optional<PlumageValidation>& v, const MemoryUsage& memory = {});
    // Several meshes dressed as one system: each one's own figures, in
    // `meshes` (the pairs of a mesh are those with at least one of its
    // feathers, so a pair across two meshes counts in both).
    void set_parts(const std::vector<MeshPart>& parts);
    void set_part_static(size_t part, const PlumagePartStats& s, const std::optional<PlumageValidation>& v);
    void add_part_frame(size_t part, size_t index, const PlumagePartStats& s, const std::optional<PlumageValidation>& v);
    // The process's memory at a named point of the run ("after_load", "after_create").
    void set_memory(const std::string& phase, const MemoryUsage& m);
    // Host-measured wall times of the run's phases.
    void set_timing(const std::string& key, double seconds) { timing_[key] = seconds; }

    nlohmann::ordered_json to_json() const;
    void write(const std::string& path) const;  // throws OutputError

private:
    nlohmann::ordered_json summary() const;
    nlohmann::ordered_json part_json(size_t part) const;

    nlohmann::ordered_json subject_ = nlohmann::ordered_json::object();
    size_t feathers_ = 0;
    nlohmann::ordered_json sampling_;
    nlohmann::ordered_json ordering_;
    nlohmann::ordered_json static_;
    nlohmann::ordered_json memory_ = nlohmann::ordered_json::object();
    nlohmann::ordered_json frames_ = nlohmann::ordered_json::array();
    nlohmann::ordered_json timing_ = nlohmann::ordered_json::object();
    struct Part {
        nlohmann::ordered_json subject;
        uint64_t feathers = 0;
        nlohmann::ordered_json static_figures;
        nlohmann::ordered_json frames = nlohmann::ordered_json::array();
    };
    std::vector<Part> parts_;
};

// Every field of a library configuration, by name (theta in degrees).
nlohmann::ordered_json config_to_json(const PlumageConfig& cfg);

// A float as the shortest decimal that reads back to it (no 0.100000001 noise).
double tidy(float v);

}  // namespace plumage_host
