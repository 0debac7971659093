// A thin C++ layer over the Plumage C ABI: an owning handle, statuses
// turned into LibraryError, the copy-out protocol and the stats queries.
#pragma once

#include "animated_mesh.h"
#include "plumage.h"

#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace plumage_host {

struct SystemDeleter {
    void operator()(PlumageSystem* sys) const noexcept { plumage_system_destroy(sys); }
};
using SystemHandle = std::unique_ptr<PlumageSystem, SystemDeleter>;

// A library call failed (exit 4): the call, the status and the library's message.
class LibraryError : public std::runtime_error {
public:
    LibraryError(const std::string& call, uint32_t status, const std::string& message);
    uint32_t status() const { return status_; }

private:
    uint32_t status_;
};

// The library's message for the last failure on `sys` (NULL: on this thread, without a system).
std::string last_error(const PlumageSystem* sys);

// Throws LibraryError unless status is PLUMAGE_STATUS_OK.
void check(uint32_t status, const PlumageSystem* sys, const char* call);

// Fails unless the loaded library speaks this header's ABI.
void check_abi();

// Optional per-vertex maps of the mesh (empty: none): multipliers of the
// root spacing (0 = bare skin), feather length and width, and flow
// directions (xyz per vertex, at the rest pose).
struct VertexMaps {
    std::vector<float> spacing;
    std::vector<float> length;
    std::vector<float> width;
    std::vector<float> flow;
    std::vector<float> layer;  // painted layers: the higher lies on top
    std::optional<SkinSkeleton> skeleton;  // the flow follows its bones
    std::vector<uint32_t> feather_type;    // per vertex, an index into feather_types
    std::vector<uint32_t> feather_types;   // PLUMAGE_PRESET_* of each type
};

SystemHandle create_system(const PlumageConfig& cfg, const std::vector<float>& positions, const std::vector<uint32_t>& indices,
                           const VertexMaps& maps = {});

std::vector<PlumageFeather> feathers(const PlumageSystem& sys);
std::vector<float> feather_triangles(const PlumageSystem& sys);

// Every feather as a mesh (plumage_system_feather_geometry): feather after
// feather in the order of feathers(), each with vertex_counts[f] vertices.
struct FeatherMeshData {
    std::vector<float> positions;         // xyz per vertex
    std::vector<float> normals;           // xyz per vertex, unit, away from the skin
    std::vector<float> uvs;               // (u along the shaft, v across the vanes) per vertex
    std::vector<uint32_t> indices;        // three per triangle, into the whole vertex array
    std::vector<uint32_t> vertex_counts;  // per feather
    std::vector<uint8_t> placed;          // per feather: 0 when left out (collapsed to its root)
};
FeatherMeshData feather_mesh(const PlumageSystem& sys);

// One PlumageFeatherInstance per feather, in the order of feathers().
std::vector<PlumageFeatherInstance> feather_instances(const PlumageSystem& sys);

// The template card every record places (plumage_system_feather_template).
struct FeatherCard {
    uint32_t segments = 0;
    float vane_split = 0;
    std::vector<float> positions;           // xyz per vertex, unit length and width
    std::vector<float> uvs;                 // (u, v) per vertex
    std::vector<uint32_t> vertex_segments;  // the shaft segment carrying each vertex
    std::vector<uint32_t> indices;          // three per triangle
};
FeatherCard feather_template(const PlumageSystem& sys);

// The feathers the last call may have changed (increasing), and whether
// that is every feather (after create, a load or a seek that loaded).
struct ChangedFeathers {
    std::vector<uint32_t> indices;
    bool all = false;
};
ChangedFeathers changed_feathers(const PlumageSystem& sys);

// Figures the library has computed; std::nullopt when it answers NOT_AVAILABLE.
std::optional<PlumageSamplingStats> sampling_stats(const PlumageSystem& sys);
std::optional<PlumageOrderingStats> ordering_stats(const PlumageSystem& sys);
std::optional<PlumageFrameStats> frame_stats(const PlumageSystem& sys);
std::optional<PlumageValidation> validate(const PlumageSystem& sys);
// The same restricted to the caller's triangles first .. first + count (one
// of several meshes dressed as one system).
PlumagePartStats part_stats(const PlumageSystem& sys, size_t first_triangle, size_t triangle_count);
std::optional<PlumageValidation> validate_part(const PlumageSystem& sys, size_t first_triangle, size_t triangle_count);

}  // namespace plumage_host

// Whether the library wrote `field` of a stats struct: it sets struct_size
// to the bytes it filled, which an older library may keep below sizeof.
#define PLUMAGE_FILLED(stats, field) \
    ((stats).struct_size >= offsetof(std::decay_t<decltype(stats)>, field) + sizeof((stats).field))
