// The command line of plumage_gltf.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace plumage_host {

enum class ValidateWhen { Every, Last, None };

// A per-vertex map read from a vertex attribute of the glTF mesh, from
// component `first` of `attribute` on (0 for a scalar attribute): one
// value per vertex for a multiplier, three for a direction.
struct VertexMapSpec {
    std::string attribute;  // empty: no map
    int first = 0;
    std::string option;  // the option that asked for it (for messages)
};

struct Options {
    std::string input;  // empty: the built-in procedural model
    std::optional<std::array<uint32_t, 2>> model_resolution;  // rings, segments of the built-in model
    std::vector<std::string> meshes;  // --mesh, in order (empty: the default mesh; "all": every deforming one)
    std::string animation;
    double fps = 30;
    double start = 0;                // seconds into the clip of the first frame
    std::optional<uint64_t> frames;  // default: the rest of the clip
    // Library settings; unset ones keep plumage_config_init's defaults.
    std::optional<uint32_t> feathers;
    std::optional<float> spacing;
    std::optional<uint32_t> sampler;
    std::optional<float> theta_deg;
    std::optional<uint64_t> seed;
    std::optional<std::array<float, 3>> flow;
    std::optional<std::array<float, 3>> flow_source;
    std::optional<uint32_t> mode;
    std::optional<float> drift_tolerance_deg;
    std::optional<float> settle_rate_deg;
    std::optional<float> curvature_min_scale;
    std::optional<uint32_t> preset;
    std::optional<uint32_t> shaft_segments;
    std::optional<float> bend_limit_deg;
    std::optional<float> fluffiness_deg;
    std::optional<uint32_t> threads;
    std::optional<uint64_t> memory_limit_mib;
    // Per-vertex maps from vertex attributes (glTF input only).
    VertexMapSpec spacing_map;
    VertexMapSpec length_map;
    VertexMapSpec width_map;
    VertexMapSpec flow_map;
    VertexMapSpec layer_map;
    VertexMapSpec type_map;  // --type-map: per-vertex index into feather_types
    std::vector<uint32_t> feather_types;  // --feather-types: PLUMAGE_PRESET_* per type
    bool skeleton_flow = true;  // --skeleton-flow on|off
    ValidateWhen validate = ValidateWhen::Last;
    std::string out;
    std::string report;
    std::string poses;  // --poses FILE: the rest mesh, config, maps and frames handed to the library
    std::string instances;  // --instances DIR: records, changed lists and the card for a renderer (viewer/)
    bool help = false;
    bool version = false;
};

// Parses argv (throws UsageError with a one-line reason).
Options parse_options(int argc, const char* const* argv);

std::string usage_text();
const char* validate_name(ValidateWhen when);
const char* sampler_name(uint32_t sampler);
const char* mode_name(uint32_t mode);

}  // namespace plumage_host
