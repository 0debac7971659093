#include "options.h"

#include "errors.h"
#include "plumage.h"

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <limits>

namespace plumage_host {
namespace {

constexpr uint64_t kMaxResolution = 4096;  // 2 * 4096 * 4094 triangles at most

[[noreturn]] void bad(const std::string& option, const std::string& value, const std::string& want) {
    throw UsageError(option + " " + value + ": expected " + want);
}

uint64_t parse_unsigned(const std::string& option, const std::string& text, uint64_t max) {
    if (text.empty() || text[0] < '0' || text[0] > '9') bad(option, text, "a non-negative integer");
    errno = 0;
    char* end = nullptr;
    const unsigned long long v = std::strtoull(text.c_str(), &end, 10);
    if (errno != 0 || *end != '\0' || v > max) bad(option, text, "an integer from 0 to " + std::to_string(max));
    return v;
}

double parse_real(const std::string& option, const std::string& text) {
    errno = 0;
    char* end = nullptr;
    const double v = std::strtod(text.c_str(), &end);
    if (text.empty() || errno != 0 || *end != '\0' || !std::isfinite(v)) bad(option, text, "a finite number");
    return v;
}

float parse_float(const std::string& option, const std::string& text) {
    const double v = parse_real(option, text);
    if (std::fabs(v) > std::numeric_limits<float>::max()) bad(option, text, "a number in float range");
    return static_cast<float>(v);
}

// Exactly N comma-separated fields (`want` names them in the error).
template <size_t N>
std::array<std::string, N> split_fields(const std::string& option, const std::string& text, const char* want) {
    std::array<std::string, N> fields;
    size_t start = 0;
    for (size_t i = 0; i < N; ++i) {
        const size_t comma = text.find(',', start);
        if ((i + 1 < N) != (comma != std::string::npos)) bad(option, text, want);
        fields[i] = text.substr(start, i + 1 < N ? comma - start : std::string::npos);
        start = comma + 1;
    }
    return fields;
}

std::array<float, 3> parse_vector(const std::string& option, const std::string& text) {
    const std::array<std::string, 3> f = split_fields<3>(option, text, "X,Y,Z");
    return {parse_float(option, f[0]), parse_float(option, f[1]), parse_float(option, f[2])};
}

// RINGS,SEGMENTS of the built-in model, each from 3 to kMaxResolution.
std::array<uint32_t, 2> parse_resolution(const std::string& option, const std::string& text) {
    const std::array<std::string, 2> f = split_fields<2>(option, text, "RINGS,SEGMENTS");
    std::array<uint32_t, 2> v{};
    for (size_t i = 0; i < 2; ++i) {
        const uint64_t n = parse_unsigned(option, f[i], UINT64_MAX);
        if (n < 3 || n > kMaxResolution) bad(option, text, "RINGS,SEGMENTS, each from 3 to " + std::to_string(kMaxResolution));
        v[i] = static_cast<uint32_t>(n);
    }
    return v;
}

// NAME or NAME:C (C = 0..3, the component of a vector attribute; default 0).
VertexMapSpec parse_map(const std::string& option, const std::string& text) {
    VertexMapSpec m;
    m.option = option;
    m.attribute = text;
    const size_t colon = text.rfind(':');
    if (colon != std::string::npos) {
        const std::string c = text.substr(colon + 1);
        if (c.size() != 1 || c[0] < '0' || c[0] > '3') bad(option, text, "NAME or NAME:C with C from 0 to 3");
        m.first = c[0] - '0';
        m.attribute.resize(colon);
    }
    if (m.attribute.empty()) bad(option, text, "a vertex attribute name");
    return m;
}

template <size_t N>
uint32_t parse_choice(const std::string& option, const std::string& text, const char* const (&names)[N], const uint32_t (&values)[N]) {
    std::string want;
    for (size_t i = 0; i < N; ++i) {
        if (text == names[i]) return values[i];
        want += (i ? "|" : "") + std::string(names[i]);
    }
    bad(option, text, want);
}

bool takes_value(const std::string& option) {
    static const char* const kOptions[] = {"--mesh", "--animation", "--fps",  "--start", "--frames",  "--feathers", "--spacing", "--sampler",
                                           "--theta", "--seed",     "--flow", "--flow-source", "--mode",    "--threads",  "--memory-limit",  "--validate", "--out", "--report", "--poses", "--instances",
                                           "--model-resolution", "--drift-tolerance", "--settle-rate", "--curvature-min-scale", "--fluffiness", "--shaft-segments", "--bend-limit", "--preset",
                                           "--spacing-map", "--length-map", "--width-map", "--flow-map", "--layer-map", "--skeleton-flow", "--type-map", "--feather-types"};
    for (const char* o : kOptions) {
        if (option == o) return true;
    }
    return false;
}

}  // namespace

const char* validate_name(ValidateWhen when) {
    switch (when) {
    case ValidateWhen::Every: return "every";
    case ValidateWhen::Last: return "last";
    default: return "none";
    }
}

const char* sampler_name(uint32_t sampler) {
    return sampler == PLUMAGE_SAMPLER_GUIDED ? "guided" : sampler == PLUMAGE_SAMPLER_RANDOM ? "random" : "unknown";
}

const char* mode_name(uint32_t mode) {
    switch (mode) {
    case PLUMAGE_MODE_INCREMENTAL: return "incremental";
    case PLUMAGE_MODE_LEGACY: return "legacy";
    case PLUMAGE_MODE_REBUILD: return "rebuild";
    default: return "unknown";
    }
}

std::string usage_text() {
    return "usage: plumage_gltf [INPUT.glb|INPUT.gltf] [options]\n"
           "  no INPUT             the built-in procedural model (a swimming body, 6016 triangles)\n"
           "  --model-resolution RINGS,SEGMENTS   the built-in model's cross-sections along the body and vertices\n"
           "                       around each (default 96,32); 2*SEGMENTS*(RINGS-2) triangles: 502,200 gives 200000\n"
           "  --mesh NAME|I|all    mesh to dress (default: the largest skinned or morphed mesh); repeat it to dress\n"
           "                       several meshes in one run, or `all` for every skinned or morphed mesh\n"
           "  --animation NAME|I   clip to play (default 0)\n"
           "  --fps F              sampling rate of the clip (default 30)\n"
           "  --start S            seconds into the clip of the first frame (default 0): a busy window of a long clip\n"
           "  --frames N           frames to step (default: the rest of the clip); 0 = rest pose only\n"
           "  --feathers N         target feather count (or --spacing D: root spacing in model units)\n"
           "  --sampler guided|random   --theta DEG   --seed S   --flow X,Y,Z\n"
           "  --flow-source X,Y,Z  feathers flow away from this point along the surface (e.g. the head); with no\n"
           "                       --flow, --flow-source or --flow-map, a skinned mesh's feathers follow its bones\n"
           "                       from the head down the trunk and each limb; other meshes flow away from the\n"
           "                       front-most rest vertex (glTF models face +Z; the built-in model faces -X)\n"
           "  --skeleton-flow on|off   off: a skinned mesh flows from its front-most vertex too (default on)\n"
           "  --mode incremental|legacy|rebuild   --threads T (0 = all cores)\n"
           "  --memory-limit MIB   most heap the library's system may hold (default: no limit); create or a step\n"
           "                       that would pass it is refused (LIMIT_EXCEEDED)\n"
           "  --drift-tolerance DEG   incremental: how far a feather may drift before it is readjusted (default 17.2;\n"
           "                       every moved feather is checked exactly each frame); at most 2.86 (theta_s) = the paper's rule\n"
           "  --settle-rate DEG    incremental: most a readjusted feather settles toward its solved pose in a frame\n"
           "                       (default 2; 0 = at once); lifting clear of a collision is never delayed\n"
           "  --curvature-min-scale S   smallest spacing factor where the surface bends tighter than a feather\n"
           "                       (default 0.4; 1 = uniform spacing)\n"
           "  --fluffiness DEG     extra pitch added to every feather (a bent one's root segment) (default 0)\n"
           "  --preset feathers|kite|scales   the library's defaults: contour feathers that lie down (default; bent\n"
           "                       shafts; `sleek` is the same), kite (the paper's rigid feather: cheaper, stands off the\n"
           "                       body) or fish scales (short, wide, nearly rigid, staggered rows); later options override them\n"
           "  --shaft-segments S   shaft segments of a feather, 1 to 4 (default 4; 1 = the rigid kite): more lets it drape\n"
           "  --bend-limit DEG     largest bend at each shaft joint (default 22.9)\n"
           "  --spacing-map NAME[:C]   per-vertex spacing multiplier from vertex attribute NAME (component C of a\n"
           "                       vector, default 0; e.g. _FEATHER_DENSITY or COLOR_0:0): 2 = half as dense, 0 = bare skin\n"
           "  --length-map NAME[:C]  --width-map NAME[:C]   per-vertex feather length and width multipliers\n"
           "  --flow-map NAME[:C]  per-vertex flow direction from components C..C+2 of vertex attribute NAME\n"
           "                       (e.g. a custom _FLOW), in the mesh's own space; overrides --flow and --flow-source\n"
           "  --layer-map NAME[:C]  per-vertex layer: where neighbours' layers differ, the higher lies on top\n"
           "  --type-map NAME[:C]  per-vertex feather type (rounded), an index into --feather-types\n"
           "  --feather-types P,P,...   the types' proportions from presets feathers|scales|kite (default feathers,scales)\n"
           "  --validate every|last|none   exact validation per frame (default last; not in step time)\n"
           "  --out FILE.glb       write the body and its animated feathers\n"
           "  --report FILE.json   write the machine-readable report\n"
           "  --poses FILE         write the library's input (rest mesh, config, maps, every frame's positions)\n"
           "                       for `python -m plumage dress` (format in gltf_host/pose_writer.h)\n"
           "  --instances DIR      write what a renderer draws instanced feathers from (viewer/): the template card,\n"
           "                       each frame's 36-byte records, changed-feather list and body positions, and the\n"
           "                       copied-out feathers of the rest pose and the last frame (format in\n"
           "                       gltf_host/instance_writer.h)\n"
           "  --version, --help\n"
           "exit codes: 0 success, 1 output not written, 2 usage error, 3 unreadable or unsupported input,\n"
           "            4 library error\n";
}

Options parse_options(int argc, const char* const* argv) {
    Options o;
    for (int i = 1; i < argc; ++i) {
        std::string arg = argv[i];
        if (arg.size() < 2 || arg[0] != '-') {
            if (!o.input.empty()) throw UsageError("more than one input file: " + o.input + ", " + arg);
            o.input = arg;
            continue;
        }
        if (arg == "-h" || arg == "--help") {
            o.help = true;
            continue;
        }
        if (arg == "--version") {
            o.version = true;
            continue;
        }
        std::string value;
        const size_t eq = arg.find('=');
        const bool inline_value = eq != std::string::npos;
        if (inline_value) {
            value = arg.substr(eq + 1);
            arg.resize(eq);
        }
        if (!takes_value(arg)) throw UsageError("unknown option " + arg);
        if (!inline_value) {
            if (i + 1 >= argc) throw UsageError(arg + ": missing value");
            value = argv[++i];
        }
        if (arg == "--mesh") o.meshes.push_back(value);
        else if (arg == "--animation") o.animation = value;
        else if (arg == "--fps") {
            o.fps = parse_real(arg, value);
            if (!(o.fps > 0) || o.fps > 1e4) bad(arg, value, "a rate above 0 and at most 10000");
        } else if (arg == "--start") {
            o.start = parse_real(arg, value);
            if (!(o.start >= 0) || o.start > 1e7) bad(arg, value, "seconds from 0 to 10000000");
        } else if (arg == "--frames") o.frames = parse_unsigned(arg, value, 10000000);
        else if (arg == "--feathers") o.feathers = static_cast<uint32_t>(parse_unsigned(arg, value, UINT32_MAX));
        else if (arg == "--spacing") o.spacing = parse_float(arg, value);
        else if (arg == "--sampler") o.sampler = parse_choice(arg, value, {"guided", "random"}, {PLUMAGE_SAMPLER_GUIDED, PLUMAGE_SAMPLER_RANDOM});
        else if (arg == "--theta") o.theta_deg = parse_float(arg, value);
        else if (arg == "--seed") o.seed = parse_unsigned(arg, value, UINT64_MAX);
        else if (arg == "--flow") o.flow = parse_vector(arg, value);
        else if (arg == "--flow-source") o.flow_source = parse_vector(arg, value);
        else if (arg == "--mode") {
            o.mode = parse_choice(arg, value, {"incremental", "legacy", "rebuild"}, {PLUMAGE_MODE_INCREMENTAL, PLUMAGE_MODE_LEGACY, PLUMAGE_MODE_REBUILD});
        } else if (arg == "--drift-tolerance") o.drift_tolerance_deg = parse_float(arg, value);
        else if (arg == "--settle-rate") o.settle_rate_deg = parse_float(arg, value);
        else if (arg == "--curvature-min-scale") o.curvature_min_scale = parse_float(arg, value);
        else if (arg == "--fluffiness") o.fluffiness_deg = parse_float(arg, value);
        else if (arg == "--preset") o.preset = parse_choice(arg, value, {"feathers", "sleek", "kite", "scales"}, {PLUMAGE_PRESET_FEATHERS, PLUMAGE_PRESET_SLEEK, PLUMAGE_PRESET_KITE, PLUMAGE_PRESET_SCALES});
        else if (arg == "--shaft-segments") o.shaft_segments = static_cast<uint32_t>(parse_unsigned(arg, value, UINT32_MAX));
        else if (arg == "--bend-limit") o.bend_limit_deg = parse_float(arg, value);
        else if (arg == "--threads") o.threads = static_cast<uint32_t>(parse_unsigned(arg, value, UINT32_MAX));
        else if (arg == "--memory-limit") o.memory_limit_mib = parse_unsigned(arg, value, UINT64_MAX >> 20);
        else if (arg == "--validate") {
            const uint32_t v = parse_choice(arg, value, {"every", "last", "none"}, {0u, 1u, 2u});
            o.validate = v == 0 ? ValidateWhen::Every : v == 1 ? ValidateWhen::Last : ValidateWhen::None;
        } else if (arg == "--spacing-map") o.spacing_map = parse_map(arg, value);
        else if (arg == "--length-map") o.length_map = parse_map(arg, value);
        else if (arg == "--width-map") o.width_map = parse_map(arg, value);
        else if (arg == "--flow-map") o.flow_map = parse_map(arg, value);
        else if (arg == "--layer-map") o.layer_map = parse_map(arg, value);
        else if (arg == "--type-map") o.type_map = parse_map(arg, value);
        else if (arg == "--feather-types") {
            o.feather_types.clear();
            std::string rest = value;
            while (true) {
                const size_t comma = rest.find(',');
                o.feather_types.push_back(parse_choice(arg, rest.substr(0, comma), {"feathers", "sleek", "kite", "scales"},
                                                       {PLUMAGE_PRESET_FEATHERS, PLUMAGE_PRESET_SLEEK, PLUMAGE_PRESET_KITE, PLUMAGE_PRESET_SCALES}));
                if (comma == std::string::npos) break;
                rest = rest.substr(comma + 1);
            }
        }
        else if (arg == "--skeleton-flow") o.skeleton_flow = parse_choice(arg, value, {"on", "off"}, {1u, 0u}) != 0;
        else if (arg == "--model-resolution") o.model_resolution = parse_resolution(arg, value);
        else if (arg == "--out") o.out = value;
        else if (arg == "--report") o.report = value;
        else if (arg == "--poses") o.poses = value;
        else if (arg == "--instances") o.instances = value;
        if (value.empty() && (arg == "--out" || arg == "--report" || arg == "--poses" || arg == "--instances" || arg == "--mesh" || arg == "--animation")) throw UsageError(arg + ": empty value");
    }
    if (o.feathers && o.spacing) throw UsageError("--feathers and --spacing are alternatives: give one");
    for (const VertexMapSpec* m : {&o.spacing_map, &o.length_map, &o.width_map, &o.flow_map, &o.layer_map, &o.type_map}) {
        if (!m->attribute.empty() && o.input.empty()) throw UsageError(m->option + " reads a vertex attribute of a glTF input; the built-in model has none");
    }
    if (o.model_resolution && !o.input.empty()) throw UsageError("--model-resolution applies to the built-in model only, not to " + o.input);
    return o;
}

}  // namespace plumage_host
