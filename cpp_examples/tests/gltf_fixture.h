// Small glTF files written by hand for the tests: one binary buffer plus a
// JSON document the test fills in directly, saved as .glb or as .gltf with
// an embedded (data URI) or external (.bin) buffer. Independent of
// tinygltf's writer, so the tests control every byte the host reads.
#pragma once

#include <nlohmann/json.hpp>

#include <cstdint>
#include <string>
#include <vector>

namespace plumage_test {

enum class GltfFormat { Glb, Embedded, External };

class GltfFixture {
public:
    GltfFixture();

    // Appends raw bytes (4-byte aligned) as a buffer view; returns its index.
    int view(const void* data, size_t bytes, size_t stride = 0);
    template <class T>
    int view(const std::vector<T>& v, size_t stride = 0) {
        return view(v.data(), v.size() * sizeof(T), stride);
    }

    // An accessor on `view` (-1: no buffer view). `type` is "SCALAR", "VEC3", ...
    int accessor(int view, int component_type, size_t count, const std::string& type, size_t byte_offset = 0, bool normalized = false);

    // Tightly packed float data as a new view and accessor, with min and max.
    int floats(const std::vector<float>& values, const std::string& type);
    // Sets an accessor's min and max from the values it reads (n per element).
    void bounds(int accessor, const std::vector<float>& values, size_t n);
    int u8(const std::vector<uint8_t>& values, const std::string& type, bool normalized = false);
    int u16(const std::vector<uint16_t>& values, const std::string& type, bool normalized = false);

    // The document: add nodes, meshes, skins, animations, scenes directly.
    nlohmann::json& doc() { return doc_; }

    // Appends `item` to the array doc[key] and returns its index.
    int add(const std::string& key, nlohmann::json item);

    // One node holding `mesh`, the whole scene.
    void single_node_scene(int mesh);

    void write(const std::string& path, GltfFormat format) const;

private:
    nlohmann::json doc_;
    std::vector<uint8_t> bin_;
};

// Component type numbers of glTF.
constexpr int kByte = 5120, kUByte = 5121, kShort = 5122, kUShort = 5123, kUInt = 5125, kFloat = 5126;

}  // namespace plumage_test
