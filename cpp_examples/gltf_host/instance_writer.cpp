#include "instance_writer.h"

#include "errors.h"

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdio>
#include <filesystem>
#include <fstream>

namespace plumage_host {
namespace {

static_assert(sizeof(PlumageFeatherInstance) == 36, "the record layout the viewer reads");

std::string numbered(const char* stem, size_t k) {
    char name[64];
    std::snprintf(name, sizeof name, "%s_%04zu.bin", stem, k);
    return name;
}

template <class T>
std::pair<const void*, size_t> bytes_of(const std::vector<T>& v) {
    return {v.data(), v.size() * sizeof(T)};
}

nlohmann::ordered_json field(size_t offset, const char* type, int count) {
    return nlohmann::ordered_json{{"offset", offset}, {"type", type}, {"count", count}};
}

}  // namespace

InstanceWriter::InstanceWriter(const std::string& dir, const PlumageSystem& sys, const std::vector<float>& body_rest,
                               const std::vector<uint32_t>& body_indices)
    : dir_(dir) {
    std::error_code ec;
    std::filesystem::create_directories(dir_, ec);
    if (!std::filesystem::is_directory(dir_)) throw OutputError("cannot create directory " + dir_);
    const FeatherCard card = feather_template(sys);
    card_vertices_ = card.vertex_segments.size();
    card_triangles_ = card.indices.size() / 3;
    write_file("template.bin", {bytes_of(card.positions), bytes_of(card.uvs), bytes_of(card.vertex_segments), bytes_of(card.indices)});
    write_file("body_indices.bin", {bytes_of(body_indices)});
    check(plumage_system_feather_count(&sys, &feathers_), &sys, "plumage_system_feather_count");

    std::array<float, 3> lo{0, 0, 0}, hi{0, 0, 0};
    for (size_t v = 0; v < body_rest.size() / 3; ++v) {
        for (size_t a = 0; a < 3; ++a) {
            const float x = body_rest[3 * v + a];
            lo[a] = v == 0 ? x : std::min(lo[a], x);
            hi[a] = v == 0 ? x : std::max(hi[a], x);
        }
    }
    manifest_ = {
        {"format", "plumage-instances"},
        {"version", 1},
        {"plumage_version", plumage_version()},
        {"feathers", feathers_},
        {"record_bytes", sizeof(PlumageFeatherInstance)},
        {"record_layout",
         {{"root", field(offsetof(PlumageFeatherInstance, root), "float32", 3)},
          {"rotation", field(offsetof(PlumageFeatherInstance, rotation), "int16", 4)},
          {"length", field(offsetof(PlumageFeatherInstance, length), "float32", 1)},
          {"width", field(offsetof(PlumageFeatherInstance, width), "float32", 1)},
          {"bends", field(offsetof(PlumageFeatherInstance, bends), "int16", 3)}}},
        {"bend_range", PLUMAGE_INSTANCE_BEND_RANGE},
        {"template",
         {{"file", "template.bin"}, {"segments", card.segments}, {"vertices", card_vertices_}, {"triangles", card_triangles_}, {"vane_split", card.vane_split}}},
        {"body",
         {{"indices", "body_indices.bin"}, {"vertices", body_rest.size() / 3}, {"triangles", body_indices.size() / 3}, {"rest_min", lo}, {"rest_max", hi}}},
    };
}

void InstanceWriter::write_file(const std::string& name, const std::vector<std::pair<const void*, size_t>>& parts) const {
    const std::string path = (std::filesystem::path(dir_) / name).string();
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    for (const auto& [data, size] : parts) {
        if (size > 0) out.write(static_cast<const char*>(data), static_cast<std::streamsize>(size));
    }
    out.close();
    if (!out) throw OutputError("cannot write " + path);
}

void InstanceWriter::add_frame(const PlumageSystem& sys, double time, const std::vector<float>& body, bool with_geometry) {
    const size_t k = frames_.size();
    const std::vector<PlumageFeatherInstance> records = feather_instances(sys);
    const ChangedFeathers changed = changed_feathers(sys);
    if (records.size() != feathers_) throw OutputError("the feather count changed between frames");
    nlohmann::ordered_json frame = {{"index", k}, {"time", time < 0 ? nlohmann::ordered_json(nullptr) : nlohmann::ordered_json(time)}};
    frame["records"] = numbered("records", k);
    write_file(frame["records"], {bytes_of(records)});
    frame["changed"] = numbered("changed", k);
    frame["changed_count"] = changed.indices.size();
    frame["all"] = changed.all;
    write_file(frame["changed"], {bytes_of(changed.indices)});
    frame["body"] = numbered("body", k);
    write_file(frame["body"], {bytes_of(body)});
    if (with_geometry) {
        const FeatherMeshData g = feather_mesh(sys);
        if (g.positions.size() != 3 * feathers_ * card_vertices_ || g.indices.size() != 3 * feathers_ * card_triangles_) {
            throw OutputError("the copied-out geometry does not have the card's vertex and triangle counts");
        }
        frame["geometry"] = numbered("geometry", k);
        write_file(frame["geometry"], {bytes_of(g.positions), bytes_of(g.normals), bytes_of(g.uvs), bytes_of(g.indices)});
    }
    frames_.push_back(std::move(frame));
}

void InstanceWriter::finish() {
    manifest_["frames"] = frames_;
    const std::string path = (std::filesystem::path(dir_) / "manifest.json").string();
    std::ofstream out(path, std::ios::trunc);
    out << manifest_.dump(1) << '\n';
    out.close();
    if (!out) throw OutputError("cannot write " + path);
}

}  // namespace plumage_host
