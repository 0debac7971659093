#include "gltf_fixture.h"

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <stdexcept>

namespace plumage_test {
namespace {

std::string base64(const std::vector<uint8_t>& in) {
    static const char* const kAlphabet = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    std::string out;
    for (size_t i = 0; i < in.size(); i += 3) {
        const uint32_t n = (uint32_t{in[i]} << 16) | (i + 1 < in.size() ? uint32_t{in[i + 1]} << 8 : 0) | (i + 2 < in.size() ? in[i + 2] : 0);
        out += kAlphabet[(n >> 18) & 63];
        out += kAlphabet[(n >> 12) & 63];
        out += i + 1 < in.size() ? kAlphabet[(n >> 6) & 63] : '=';
        out += i + 2 < in.size() ? kAlphabet[n & 63] : '=';
    }
    return out;
}

void put_u32(std::vector<uint8_t>& out, uint32_t v) {
    for (int i = 0; i < 4; ++i) out.push_back(static_cast<uint8_t>(v >> (8 * i)));
}

void write_bytes(const std::string& path, const void* data, size_t size) {
    std::ofstream out(path, std::ios::binary);
    out.write(static_cast<const char*>(data), static_cast<std::streamsize>(size));
    if (!out) throw std::runtime_error("cannot write " + path);
}

}  // namespace

GltfFixture::GltfFixture() : doc_({{"asset", {{"version", "2.0"}, {"generator", "plumage tests"}}}}) {}

int GltfFixture::add(const std::string& key, nlohmann::json item) {
    nlohmann::json& list = doc_[key];
    if (list.is_null()) list = nlohmann::json::array();
    list.push_back(std::move(item));
    return static_cast<int>(list.size() - 1);
}

int GltfFixture::view(const void* data, size_t bytes, size_t stride) {
    bin_.resize((bin_.size() + 3) / 4 * 4, 0);
    nlohmann::json v = {{"buffer", 0}, {"byteOffset", bin_.size()}, {"byteLength", bytes}};
    if (stride != 0) v["byteStride"] = stride;
    const auto* p = static_cast<const uint8_t*>(data);
    bin_.insert(bin_.end(), p, p + bytes);
    return add("bufferViews", v);
}

int GltfFixture::accessor(int view, int component_type, size_t count, const std::string& type, size_t byte_offset, bool normalized) {
    nlohmann::json a = {{"componentType", component_type}, {"count", count}, {"type", type}};
    if (view >= 0) a["bufferView"] = view;
    if (byte_offset != 0) a["byteOffset"] = byte_offset;
    if (normalized) a["normalized"] = true;
    return add("accessors", a);
}

namespace {
size_t components(const std::string& type) {
    return type == "SCALAR" ? 1 : type == "VEC2" ? 2 : type == "VEC3" ? 3 : type == "VEC4" ? 4 : type == "MAT4" ? 16 : 0;
}
}  // namespace

int GltfFixture::floats(const std::vector<float>& values, const std::string& type) {
    const size_t n = components(type);
    const int index = accessor(view(values), kFloat, values.size() / n, type);
    bounds(index, values, n);
    return index;
}

void GltfFixture::bounds(int accessor, const std::vector<float>& values, size_t n) {
    // min and max per component (required for POSITION and animation inputs).
    std::vector<float> lo(values.begin(), values.begin() + static_cast<long>(std::min(n, values.size())));
    std::vector<float> hi = lo;
    for (size_t i = 0; i < values.size(); ++i) lo[i % n] = std::min(lo[i % n], values[i]), hi[i % n] = std::max(hi[i % n], values[i]);
    doc_["accessors"][static_cast<size_t>(accessor)]["min"] = lo;
    doc_["accessors"][static_cast<size_t>(accessor)]["max"] = hi;
}
int GltfFixture::u8(const std::vector<uint8_t>& values, const std::string& type, bool normalized) {
    return accessor(view(values), kUByte, values.size() / components(type), type, 0, normalized);
}
int GltfFixture::u16(const std::vector<uint16_t>& values, const std::string& type, bool normalized) {
    return accessor(view(values), kUShort, values.size() / components(type), type, 0, normalized);
}

void GltfFixture::single_node_scene(int mesh) {
    const int node = add("nodes", {{"mesh", mesh}});
    doc_["scenes"] = nlohmann::json::array({{{"nodes", {node}}}});
    doc_["scene"] = 0;
}

void GltfFixture::write(const std::string& path, GltfFormat format) const {
    nlohmann::json doc = doc_;
    std::vector<uint8_t> bin = bin_;
    bin.resize((bin.size() + 3) / 4 * 4, 0);
    nlohmann::json buffer = {{"byteLength", bin.size()}};
    if (format == GltfFormat::Embedded) buffer["uri"] = "data:application/octet-stream;base64," + base64(bin);
    if (format == GltfFormat::External) {
        const std::filesystem::path bin_path = std::filesystem::path(path).replace_extension(".bin");
        write_bytes(bin_path.string(), bin.data(), bin.size());
        buffer["uri"] = bin_path.filename().string();
    }
    if (!bin.empty()) doc["buffers"] = nlohmann::json::array({buffer});
    std::string text = doc.dump();
    if (format != GltfFormat::Glb) {
        write_bytes(path, text.data(), text.size());
        return;
    }
    text.resize((text.size() + 3) / 4 * 4, ' ');  // chunks are 4-byte aligned; JSON pads with spaces
    std::vector<uint8_t> glb;
    put_u32(glb, 0x46546C67);  // "glTF"
    put_u32(glb, 2);
    put_u32(glb, static_cast<uint32_t>(12 + 8 + text.size() + (bin.empty() ? 0 : 8 + bin.size())));
    put_u32(glb, static_cast<uint32_t>(text.size()));
    put_u32(glb, 0x4E4F534A);  // "JSON"
    glb.insert(glb.end(), text.begin(), text.end());
    if (!bin.empty()) {
        put_u32(glb, static_cast<uint32_t>(bin.size()));
        put_u32(glb, 0x004E4942);  // "BIN\0"
        glb.insert(glb.end(), bin.begin(), bin.end());
    }
    write_bytes(path, glb.data(), glb.size());
}

}  // namespace plumage_test
