#include "plumage_system.h"

#include <algorithm>
#include <type_traits>

namespace plumage_host {
namespace {

// The copy-out protocol: ask the length with a NULL buffer, then copy.
template <class T>
std::vector<T> copy_out(uint32_t (*query)(const PlumageSystem*, T*, size_t, size_t*), const PlumageSystem& sys, const char* call) {
    size_t need = 0;
    const uint32_t status = query(&sys, nullptr, 0, &need);
    if (status == PLUMAGE_STATUS_OK && need == 0) return {};
    if (status != PLUMAGE_STATUS_BUFFER_TOO_SMALL) check(status, &sys, call);
    std::vector<T> out(need);
    size_t got = 0;
    check(query(&sys, out.data(), out.size(), &got), &sys, call);
    out.resize(std::min(got, need));
    return out;
}

template <class Stats>
std::optional<Stats> stats_query(uint32_t (*query)(const PlumageSystem*, Stats*), const PlumageSystem& sys, const char* call) {
    Stats stats{};
    stats.struct_size = sizeof(Stats);
    const uint32_t status = query(&sys, &stats);
    if (status == PLUMAGE_STATUS_NOT_AVAILABLE) return std::nullopt;
    check(status, &sys, call);
    return stats;
}

}  // namespace

LibraryError::LibraryError(const std::string& call, uint32_t status, const std::string& message)
    : std::runtime_error(call + " failed: " + plumage_status_name(status) + (message.empty() ? "" : ": " + message)), status_(status) {}

std::string last_error(const PlumageSystem* sys) {
    const size_t need = plumage_system_last_error(sys, nullptr, 0);
    if (need <= 1) return {};
    std::string text(need, '\0');
    plumage_system_last_error(sys, text.data(), text.size());
    text.resize(need - 1);
    return text;
}

void check(uint32_t status, const PlumageSystem* sys, const char* call) {
    if (status != PLUMAGE_STATUS_OK) throw LibraryError(call, status, last_error(sys));
}

void check_abi() {
    if (plumage_abi_version() != PLUMAGE_ABI_VERSION) {
        throw LibraryError("plumage_abi_version", PLUMAGE_STATUS_INVALID_ARGUMENT,
                           "library ABI " + std::to_string(plumage_abi_version()) + ", header ABI " + std::to_string(PLUMAGE_ABI_VERSION));
    }
}

SystemHandle create_system(const PlumageConfig& cfg, const std::vector<float>& positions, const std::vector<uint32_t>& indices,
                           const VertexMaps& maps) {
    PlumageMeshDesc mesh;
    plumage_mesh_desc_init(&mesh);
    mesh.positions = positions.data();
    mesh.vertex_count = positions.size() / 3;
    mesh.indices = indices.data();
    mesh.triangle_count = indices.size() / 3;
    // The library checks each map's length against the vertex count.
    const auto map = [](const std::vector<float>& m) { return m.empty() ? nullptr : m.data(); };
    mesh.spacing_scale = map(maps.spacing);
    mesh.length_scale = map(maps.length);
    mesh.width_scale = map(maps.width);
    mesh.orientations = map(maps.flow);
    mesh.layer = map(maps.layer);
    PlumageSkeleton skeleton{};
    if (maps.skeleton) {
        const SkinSkeleton& s = *maps.skeleton;
        skeleton.joint_count = static_cast<uint32_t>(s.joint_count());
        skeleton.influences = s.influences;
        skeleton.joint_positions = s.joint_positions.data();
        skeleton.joint_parents = s.joint_parents.data();
        skeleton.vertex_joints = s.vertex_joints.data();
        skeleton.vertex_weights = s.vertex_weights.data();
        skeleton.head_joint = -1;
        mesh.skeleton = &skeleton;
    }
    std::vector<PlumageFeatherType> types(maps.feather_types.size());
    for (size_t k = 0; k < types.size(); ++k) check(plumage_feather_type_init(&types[k], maps.feather_types[k]), nullptr, "plumage_feather_type_init");
    if (!maps.feather_type.empty()) {
        mesh.feather_type = maps.feather_type.data();
        mesh.feather_types = types.data();
        mesh.feather_type_count = static_cast<uint32_t>(types.size());
    }
    PlumageSystem* raw = nullptr;
    const uint32_t status = plumage_system_create(&cfg, &mesh, &raw);
    SystemHandle sys(raw);  // owned before anything can throw
    check(status, nullptr, "plumage_system_create");
    return sys;
}

std::vector<PlumageFeather> feathers(const PlumageSystem& sys) { return copy_out(&plumage_system_feathers, sys, "plumage_system_feathers"); }

std::vector<float> feather_triangles(const PlumageSystem& sys) {
    return copy_out(&plumage_system_feather_triangles, sys, "plumage_system_feather_triangles");
}

FeatherMeshData feather_mesh(const PlumageSystem& sys) {
    PlumageFeatherGeometry g;
    plumage_feather_geometry_init(&g);
    check(plumage_system_feather_geometry(&sys, &g), &sys, "plumage_system_feather_geometry");
    FeatherMeshData m;
    const size_t nv = static_cast<size_t>(g.vertex_count), nt = static_cast<size_t>(g.triangle_count), nf = static_cast<size_t>(g.feather_count);
    m.positions.resize(3 * nv);
    m.normals.resize(3 * nv);
    m.uvs.resize(2 * nv);
    m.indices.resize(3 * nt);
    m.vertex_counts.resize(nf);
    m.placed.resize(nf);
    g.positions = m.positions.data(), g.positions_capacity = m.positions.size();
    g.normals = m.normals.data(), g.normals_capacity = m.normals.size();
    g.uvs = m.uvs.data(), g.uvs_capacity = m.uvs.size();
    g.indices = m.indices.data(), g.indices_capacity = m.indices.size();
    g.vertex_counts = m.vertex_counts.data(), g.vertex_counts_capacity = m.vertex_counts.size();
    g.placed = m.placed.data(), g.placed_capacity = m.placed.size();
    check(plumage_system_feather_geometry(&sys, &g), &sys, "plumage_system_feather_geometry");
    return m;
}

std::vector<PlumageFeatherInstance> feather_instances(const PlumageSystem& sys) {
    return copy_out(&plumage_system_feather_instances, sys, "plumage_system_feather_instances");
}

FeatherCard feather_template(const PlumageSystem& sys) {
    PlumageFeatherTemplate t;
    plumage_feather_template_init(&t);
    check(plumage_system_feather_template(&sys, &t), &sys, "plumage_system_feather_template");
    FeatherCard c;
    c.segments = t.segments;
    c.vane_split = t.vane_split;
    c.positions.resize(3 * static_cast<size_t>(t.vertex_count));
    c.uvs.resize(2 * static_cast<size_t>(t.vertex_count));
    c.vertex_segments.resize(t.vertex_count);
    c.indices.resize(3 * static_cast<size_t>(t.triangle_count));
    t.positions = c.positions.data(), t.positions_capacity = c.positions.size();
    t.uvs = c.uvs.data(), t.uvs_capacity = c.uvs.size();
    t.vertex_segments = c.vertex_segments.data(), t.vertex_segments_capacity = c.vertex_segments.size();
    t.indices = c.indices.data(), t.indices_capacity = c.indices.size();
    check(plumage_system_feather_template(&sys, &t), &sys, "plumage_system_feather_template");
    return c;
}

ChangedFeathers changed_feathers(const PlumageSystem& sys) {
    ChangedFeathers c;
    size_t need = 0;
    uint32_t all = 0;
    const uint32_t status = plumage_system_changed_feathers(&sys, nullptr, 0, &need, &all);
    if (status != PLUMAGE_STATUS_OK && status != PLUMAGE_STATUS_BUFFER_TOO_SMALL) check(status, &sys, "plumage_system_changed_feathers");
    c.indices.resize(need);
    if (need > 0) {
        size_t got = 0;
        check(plumage_system_changed_feathers(&sys, c.indices.data(), c.indices.size(), &got, &all), &sys, "plumage_system_changed_feathers");
        c.indices.resize(std::min(got, need));
    }
    c.all = all != 0;
    return c;
}

std::optional<PlumageSamplingStats> sampling_stats(const PlumageSystem& sys) {
    return stats_query(&plumage_system_sampling_stats, sys, "plumage_system_sampling_stats");
}
std::optional<PlumageOrderingStats> ordering_stats(const PlumageSystem& sys) {
    return stats_query(&plumage_system_ordering_stats, sys, "plumage_system_ordering_stats");
}
std::optional<PlumageFrameStats> frame_stats(const PlumageSystem& sys) {
    return stats_query(&plumage_system_frame_stats, sys, "plumage_system_frame_stats");
}
std::optional<PlumageValidation> validate(const PlumageSystem& sys) { return stats_query(&plumage_system_validate, sys, "plumage_system_validate"); }

PlumagePartStats part_stats(const PlumageSystem& sys, size_t first_triangle, size_t triangle_count) {
    PlumagePartStats stats;
    plumage_part_stats_init(&stats);
    check(plumage_system_part_stats(&sys, first_triangle, triangle_count, &stats), &sys, "plumage_system_part_stats");
    return stats;
}

std::optional<PlumageValidation> validate_part(const PlumageSystem& sys, size_t first_triangle, size_t triangle_count) {
    PlumageValidation v;
    plumage_validation_init(&v);
    const uint32_t status = plumage_system_validate_part(&sys, first_triangle, triangle_count, &v);
    if (status == PLUMAGE_STATUS_NOT_AVAILABLE) return std::nullopt;
    check(status, &sys, "plumage_system_validate_part");
    return v;
}

}  // namespace plumage_host
