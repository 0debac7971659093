/*
 * plumage.hpp: an optional, header-only C++17 wrapper of the C ABI in
 * plumage.h. It adds no behaviour of its own:
 *   - plumage::System owns a PlumageSystem (RAII, move-only);
 *   - copy-out queries return std::vector (or refill one the caller keeps,
 *     so a per-frame query need not allocate);
 *   - a refused call throws plumage::Error with the status and the
 *     library's message, so a plugin needs no status checks of its own.
 * A refused call leaves the system as it was (the C ABI's rule), so a
 * caught Error leaves a usable System. Thread safety is the C ABI's: const
 * members only read and may run concurrently; the others need exclusive use.
 */
#ifndef PLUMAGE_HPP
#define PLUMAGE_HPP

#include "plumage.h"

#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace plumage {

/// A refused call: the PLUMAGE_STATUS_* code and the library's message.
class Error : public std::runtime_error {
public:
    Error(uint32_t status, const std::string& message)
        : std::runtime_error(std::string(plumage_status_name(status)) + ": " + message),
          status_(status),
          message_(message) {}
    /// The PLUMAGE_STATUS_* code.
    uint32_t status() const noexcept { return status_; }
    /// Its name ("INVALID_MESH", ...), static.
    const char* status_name() const noexcept { return plumage_status_name(status_); }
    /// The library's message alone (what() prefixes the status name).
    const std::string& message() const noexcept { return message_; }

private:
    uint32_t status_;
    std::string message_;
};

namespace detail {

/// The message of the last failure on `sys` (NULL: on this thread, for a
/// call that had no usable system).
inline std::string last_error(const PlumageSystem* sys) {
    const size_t needed = plumage_system_last_error(sys, nullptr, 0);
    if (needed <= 1) return std::string();
    std::string msg(needed, '\0');
    plumage_system_last_error(sys, &msg[0], needed);
    msg.resize(needed - 1);
    return msg;
}

inline void check(uint32_t status, const PlumageSystem* sys) {
    if (status != PLUMAGE_STATUS_OK) throw Error(status, last_error(sys));
}

/// Number of xyz triples in `floats` floats, refusing a remainder.
inline size_t vertex_triples(size_t floats) {
    if (floats % 3 != 0) {
        throw Error(PLUMAGE_STATUS_INVALID_ARGUMENT,
                    "positions holds " + std::to_string(floats) + " floats, not a multiple of 3 (xyz per vertex)");
    }
    return floats / 3;
}

/// The C ABI's copy-out convention into a vector: ask the length, size the
/// vector, copy.
template <class T, class Query>
void copy_out(const PlumageSystem* sys, std::vector<T>& out, Query query) {
    size_t len = 0;
    uint32_t st = query(static_cast<T*>(nullptr), size_t(0), &len);
    if (st == PLUMAGE_STATUS_OK) {
        out.clear();
        return;
    }
    if (st != PLUMAGE_STATUS_BUFFER_TOO_SMALL) check(st, sys);
    out.resize(len);
    size_t written = 0;
    check(query(out.data(), out.size(), &written), sys);
    out.resize(written);
}

}  // namespace detail

/// The library version ("MAJOR.MINOR.PATCH").
inline const char* version() noexcept { return plumage_version(); }

/// True when the loaded library has the ABI this header was compiled for.
inline bool abi_compatible() noexcept { return plumage_abi_version() == PLUMAGE_ABI_VERSION; }

/// The default configuration (plumage_config_init); change what you need.
inline PlumageConfig default_config() noexcept {
    PlumageConfig cfg;
    plumage_config_init(&cfg);
    return cfg;
}

/// A mesh description of caller-owned arrays (xyz per vertex, three
/// indices per triangle). The arrays are only read during create.
inline PlumageMeshDesc mesh_desc(const std::vector<float>& positions, const std::vector<uint32_t>& indices) {
    PlumageMeshDesc mesh;
    plumage_mesh_desc_init(&mesh);
    mesh.positions = positions.data();
    mesh.vertex_count = detail::vertex_triples(positions.size());
    if (indices.size() % 3 != 0) {
        throw Error(PLUMAGE_STATUS_INVALID_ARGUMENT,
                    "indices holds " + std::to_string(indices.size()) + " entries, not a multiple of 3");
    }
    mesh.indices = indices.data();
    mesh.triangle_count = indices.size() / 3;
    return mesh;
}

/// Every feather as a mesh (plumage_system_feather_geometry); see
/// PlumageFeatherGeometry for the layout.
struct FeatherGeometry {
    std::vector<float> positions;           ///< xyz per vertex
    std::vector<float> normals;             ///< unit xyz per vertex
    std::vector<float> uvs;                 ///< (u along the shaft, v across the vanes) per vertex
    std::vector<uint32_t> indices;          ///< three per triangle, into the whole vertex array
    std::vector<uint32_t> vertex_feathers;  ///< per vertex: its feather
    std::vector<uint32_t> vertex_counts;    ///< per feather
    std::vector<uint32_t> triangle_counts;  ///< per feather
    std::vector<uint8_t> placed;            ///< per feather: 1 placed, 0 left out (collapsed to its root)

    size_t feather_count() const noexcept { return vertex_counts.size(); }
    size_t vertex_count() const noexcept { return vertex_feathers.size(); }
    size_t triangle_count() const noexcept { return indices.size() / 3; }
};

/// The template card every feather is instanced from
/// (plumage_system_feather_template); see PlumageFeatherTemplate, and
/// PlumageFeatherInstance for how a record places it.
struct FeatherTemplate {
    uint32_t segments = 0;                  ///< shaft segments S
    float vane_split = 0.0f;                ///< where the vane corners sit (fraction of the length)
    std::vector<float> positions;           ///< xyz per vertex, own frame, unit length and width
    std::vector<float> uvs;                 ///< (u, v) per vertex
    std::vector<uint32_t> indices;          ///< three per triangle
    std::vector<uint32_t> vertex_segments;  ///< per vertex: the shaft segment that carries it

    size_t vertex_count() const noexcept { return vertex_segments.size(); }
    size_t triangle_count() const noexcept { return indices.size() / 3; }
};

/// An owned feathering system: created in the constructor, destroyed with
/// the object. Move-only; a moved-from System holds nothing and only its
/// destructor, assignment and get() may be used.
class System {
public:
    /// plumage_system_create; throws Error when refused.
    System(const PlumageConfig& config, const PlumageMeshDesc& rest) {
        PlumageSystem* sys = nullptr;
        detail::check(plumage_system_create(&config, &rest, &sys), nullptr);
        sys_ = sys;
    }
    /// The same, from xyz positions and triangle indices.
    System(const PlumageConfig& config, const std::vector<float>& positions, const std::vector<uint32_t>& indices)
        : System(config, mesh_desc(positions, indices)) {}

    System(const System&) = delete;
    System& operator=(const System&) = delete;
    System(System&& other) noexcept : sys_(std::exchange(other.sys_, nullptr)) {}
    System& operator=(System&& other) noexcept {
        if (this != &other) {
            plumage_system_destroy(sys_);
            sys_ = std::exchange(other.sys_, nullptr);
        }
        return *this;
    }
    ~System() { plumage_system_destroy(sys_); }

    /// The C handle, still owned by this object (NULL once moved from).
    PlumageSystem* get() const noexcept { return sys_; }
    explicit operator bool() const noexcept { return sys_ != nullptr; }

    /// plumage_system_step: the next frame, xyz per rest vertex.
    void step(const float* positions, size_t vertex_count) {
        detail::check(plumage_system_step(sys_, positions, vertex_count), sys_);
    }
    void step(const std::vector<float>& positions) {
        step(positions.data(), detail::vertex_triples(positions.size()));
    }
    /// plumage_system_evaluate: this pose from scratch.
    void evaluate(const float* positions, size_t vertex_count) {
        detail::check(plumage_system_evaluate(sys_, positions, vertex_count), sys_);
    }
    void evaluate(const std::vector<float>& positions) {
        evaluate(positions.data(), detail::vertex_triples(positions.size()));
    }

    size_t feather_count() const {
        size_t n = 0;
        detail::check(plumage_system_feather_count(sys_, &n), sys_);
        return n;
    }
    /// The vertex count every frame must give.
    size_t vertex_count() const {
        size_t n = 0;
        detail::check(plumage_system_vertex_count(sys_, &n), sys_);
        return n;
    }

    /// plumage_system_feathers.
    void feathers(std::vector<PlumageFeather>& out) const {
        detail::copy_out(sys_, out, [this](PlumageFeather* buf, size_t cap, size_t* len) {
            return plumage_system_feathers(sys_, buf, cap, len);
        });
    }
    std::vector<PlumageFeather> feathers() const {
        std::vector<PlumageFeather> out;
        feathers(out);
        return out;
    }

    /// plumage_system_feather_triangles: 18 floats (two triangles) per feather.
    void feather_triangles(std::vector<float>& out) const {
        detail::copy_out(sys_, out, [this](float* buf, size_t cap, size_t* len) {
            return plumage_system_feather_triangles(sys_, buf, cap, len);
        });
    }
    std::vector<float> feather_triangles() const {
        std::vector<float> out;
        feather_triangles(out);
        return out;
    }

    /// plumage_system_feather_geometry: every buffer, sized from the totals.
    void feather_geometry(FeatherGeometry& out) const {
        PlumageFeatherGeometry g;
        plumage_feather_geometry_init(&g);
        detail::check(plumage_system_feather_geometry(sys_, &g), sys_);
        const size_t nf = static_cast<size_t>(g.feather_count);
        const size_t nv = static_cast<size_t>(g.vertex_count);
        const size_t nt = static_cast<size_t>(g.triangle_count);
        out.positions.resize(3 * nv);
        out.normals.resize(3 * nv);
        out.uvs.resize(2 * nv);
        out.indices.resize(3 * nt);
        out.vertex_feathers.resize(nv);
        out.vertex_counts.resize(nf);
        out.triangle_counts.resize(nf);
        out.placed.resize(nf);
        g.positions = out.positions.data();
        g.positions_capacity = out.positions.size();
        g.normals = out.normals.data();
        g.normals_capacity = out.normals.size();
        g.uvs = out.uvs.data();
        g.uvs_capacity = out.uvs.size();
        g.indices = out.indices.data();
        g.indices_capacity = out.indices.size();
        g.vertex_feathers = out.vertex_feathers.data();
        g.vertex_feathers_capacity = out.vertex_feathers.size();
        g.vertex_counts = out.vertex_counts.data();
        g.vertex_counts_capacity = out.vertex_counts.size();
        g.triangle_counts = out.triangle_counts.data();
        g.triangle_counts_capacity = out.triangle_counts.size();
        g.placed = out.placed.data();
        g.placed_capacity = out.placed.size();
        detail::check(plumage_system_feather_geometry(sys_, &g), sys_);
    }
    FeatherGeometry feather_geometry() const {
        FeatherGeometry out;
        feather_geometry(out);
        return out;
    }

    /// plumage_system_feather_instances: one 36-byte record per feather.
    void feather_instances(std::vector<PlumageFeatherInstance>& out) const {
        detail::copy_out(sys_, out, [this](PlumageFeatherInstance* buf, size_t cap, size_t* len) {
            return plumage_system_feather_instances(sys_, buf, cap, len);
        });
    }
    std::vector<PlumageFeatherInstance> feather_instances() const {
        std::vector<PlumageFeatherInstance> out;
        feather_instances(out);
        return out;
    }

    /// plumage_system_feather_template: the card, every buffer.
    FeatherTemplate feather_template() const {
        PlumageFeatherTemplate t;
        plumage_feather_template_init(&t);
        detail::check(plumage_system_feather_template(sys_, &t), sys_);
        FeatherTemplate out;
        out.segments = t.segments;
        out.vane_split = t.vane_split;
        out.positions.resize(3 * size_t(t.vertex_count));
        out.uvs.resize(2 * size_t(t.vertex_count));
        out.indices.resize(3 * size_t(t.triangle_count));
        out.vertex_segments.resize(t.vertex_count);
        t.positions = out.positions.data();
        t.positions_capacity = out.positions.size();
        t.uvs = out.uvs.data();
        t.uvs_capacity = out.uvs.size();
        t.indices = out.indices.data();
        t.indices_capacity = out.indices.size();
        t.vertex_segments = out.vertex_segments.data();
        t.vertex_segments_capacity = out.vertex_segments.size();
        detail::check(plumage_system_feather_template(sys_, &t), sys_);
        return out;
    }

    /// plumage_system_changed_feathers: fills `out` with the indices of the
    /// feathers the last call may have changed; returns true when that is
    /// every feather (after create, a load or a seek that loaded).
    bool changed_feathers(std::vector<uint32_t>& out) const {
        uint32_t all = 0;
        detail::copy_out(sys_, out, [this, &all](uint32_t* buf, size_t cap, size_t* len) {
            return plumage_system_changed_feathers(sys_, buf, cap, len, &all);
        });
        return all != 0;
    }

    PlumageSamplingStats sampling_stats() const {
        return fill(plumage_sampling_stats_init, plumage_system_sampling_stats);
    }
    PlumageOrderingStats ordering_stats() const {
        return fill(plumage_ordering_stats_init, plumage_system_ordering_stats);
    }
    /// What the last create, step or evaluate did.
    PlumageFrameStats frame_stats() const { return fill(plumage_frame_stats_init, plumage_system_frame_stats); }
    /// plumage_system_validate: the exact checks on the current feathers.
    PlumageValidation validate() const { return fill(plumage_validation_init, plumage_system_validate); }
    /// plumage_system_part_stats and plumage_system_validate_part: the figures
    /// of the feathers rooted on the triangles first .. first + count (one of
    /// several meshes dressed as one system).
    PlumagePartStats part_stats(size_t first_triangle, size_t triangle_count) const {
        PlumagePartStats out;
        plumage_part_stats_init(&out);
        detail::check(plumage_system_part_stats(sys_, first_triangle, triangle_count, &out), sys_);
        return out;
    }
    PlumageValidation validate_part(size_t first_triangle, size_t triangle_count) const {
        PlumageValidation out;
        plumage_validation_init(&out);
        detail::check(plumage_system_validate_part(sys_, first_triangle, triangle_count, &out), sys_);
        return out;
    }

    /// plumage_system_save_state: the current frame as a blob.
    std::vector<uint8_t> save_state() const {
        std::vector<uint8_t> blob;
        detail::copy_out(sys_, blob, [this](uint8_t* buf, size_t cap, size_t* len) {
            return plumage_system_save_state(sys_, buf, cap, len);
        });
        return blob;
    }
    /// plumage_system_load_state.
    void load_state(const uint8_t* blob, size_t len) {
        detail::check(plumage_system_load_state(sys_, blob, len), sys_);
    }
    void load_state(const std::vector<uint8_t>& blob) { load_state(blob.data(), blob.size()); }

private:
    /// A figures struct set up by `init` and filled by `query`.
    template <class T>
    T fill(void (*init)(T*), uint32_t (*query)(const PlumageSystem*, T*)) const {
        T out;
        init(&out);
        detail::check(query(sys_, &out), sys_);
        return out;
    }

    PlumageSystem* sys_ = nullptr;
};

}  // namespace plumage

#endif /* PLUMAGE_HPP */
