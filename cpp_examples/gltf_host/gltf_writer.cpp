#include "gltf_writer.h"

#include "errors.h"

#include <tiny_gltf.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <limits>
#include <map>
#include <optional>

namespace plumage_host {
namespace {

// Appends buffer views and accessors to a one-buffer model.
class GlbBuilder {
public:
    GlbBuilder() {
        model_.asset.version = "2.0";
        model_.asset.generator = std::string("plumage_gltf (Plumage ") + plumage_version() + ")";
        model_.buffers.emplace_back();
    }

    int positions(const std::vector<float>& xyz) {
        std::vector<double> lo(3, std::numeric_limits<double>::infinity()), hi(3, -std::numeric_limits<double>::infinity());
        for (size_t i = 0; i < xyz.size(); ++i) lo[i % 3] = std::min<double>(lo[i % 3], xyz[i]), hi[i % 3] = std::max<double>(hi[i % 3], xyz[i]);
        return accessor(view(xyz.data(), xyz.size() * sizeof(float), TINYGLTF_TARGET_ARRAY_BUFFER), TINYGLTF_COMPONENT_TYPE_FLOAT,
                        xyz.size() / 3, TINYGLTF_TYPE_VEC3, lo, hi);
    }

    int vectors(const std::vector<float>& values, int type, size_t width) {
        return accessor(view(values.data(), values.size() * sizeof(float), TINYGLTF_TARGET_ARRAY_BUFFER), TINYGLTF_COMPONENT_TYPE_FLOAT,
                        values.size() / width, type, {}, {});
    }

    // Scalars of an animation sampler (vertex_data false) or a vertex attribute.
    int scalars(const std::vector<float>& values, bool with_bounds, bool vertex_data = false) {
        std::vector<double> lo, hi;
        if (with_bounds && !values.empty()) {
            const auto [a, b] = std::minmax_element(values.begin(), values.end());
            lo = {*a}, hi = {*b};
        }
        return accessor(view(values.data(), values.size() * sizeof(float), vertex_data ? TINYGLTF_TARGET_ARRAY_BUFFER : 0), TINYGLTF_COMPONENT_TYPE_FLOAT,
                        values.size(), TINYGLTF_TYPE_SCALAR, lo, hi);
    }

    int indices(const std::vector<uint32_t>& idx, size_t vertex_count) {
        if (vertex_count <= std::numeric_limits<uint16_t>::max()) {
            const std::vector<uint16_t> narrow(idx.begin(), idx.end());
            return accessor(view(narrow.data(), narrow.size() * 2, TINYGLTF_TARGET_ELEMENT_ARRAY_BUFFER), TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT,
                            idx.size(), TINYGLTF_TYPE_SCALAR, {}, {});
        }
        return accessor(view(idx.data(), idx.size() * 4, TINYGLTF_TARGET_ELEMENT_ARRAY_BUFFER), TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT, idx.size(),
                        TINYGLTF_TYPE_SCALAR, {}, {});
    }

    int material(const char* name, std::array<double, 4> color, bool double_sided) {
        tinygltf::Material m;
        m.name = name;
        m.pbrMetallicRoughness.baseColorFactor.assign(color.begin(), color.end());
        m.pbrMetallicRoughness.metallicFactor = 0.0;
        m.pbrMetallicRoughness.roughnessFactor = 0.8;
        m.doubleSided = double_sided;
        model_.materials.push_back(std::move(m));
        return static_cast<int>(model_.materials.size() - 1);
    }

    // An image stored as encoded bytes in the buffer; returns the texture's index.
    int encoded_texture(const char* name, const EncodedTexture& in) {
        tinygltf::Image image;
        image.name = name;
        image.mimeType = in.mime_type;
        image.bufferView = view(in.bytes.data(), in.bytes.size(), 0);
        model_.images.push_back(std::move(image));
        tinygltf::Sampler sampler;
        sampler.magFilter = in.mag_filter;
        sampler.minFilter = in.min_filter;
        sampler.wrapS = in.wrap_s;
        sampler.wrapT = in.wrap_t;
        model_.samplers.push_back(sampler);
        tinygltf::Texture t;
        t.name = name;
        t.source = static_cast<int>(model_.images.size() - 1);
        t.sampler = static_cast<int>(model_.samplers.size() - 1);
        model_.textures.push_back(std::move(t));
        return static_cast<int>(model_.textures.size() - 1);
    }

    tinygltf::Model& model() { return model_; }

private:
    int view(const void* data, size_t bytes, int target) {
        std::vector<unsigned char>& buffer = model_.buffers[0].data;
        buffer.resize((buffer.size() + 3) / 4 * 4, 0);  // 4-byte alignment for every view
        tinygltf::BufferView v;
        v.buffer = 0;
        v.byteOffset = buffer.size();
        v.byteLength = bytes;
        v.target = target;
        const auto* p = static_cast<const unsigned char*>(data);
        buffer.insert(buffer.end(), p, p + bytes);
        model_.bufferViews.push_back(v);
        return static_cast<int>(model_.bufferViews.size() - 1);
    }

    int accessor(int view, int component, size_t count, int type, std::vector<double> lo, std::vector<double> hi) {
        tinygltf::Accessor a;
        a.bufferView = view;
        a.componentType = component;
        a.count = count;
        a.type = type;
        a.minValues = std::move(lo);
        a.maxValues = std::move(hi);
        model_.accessors.push_back(std::move(a));
        return static_cast<int>(model_.accessors.size() - 1);
    }

    tinygltf::Model model_;
};

bool in_unit(double x) { return std::isfinite(x) && x >= 0 && x <= 1; }

int body_material(GlbBuilder& b, const BodyMaterial& in) {
    const int index = b.material(in.name.c_str(), in.base_color, in.double_sided);
    tinygltf::Material& m = b.model().materials[static_cast<size_t>(index)];
    m.pbrMetallicRoughness.metallicFactor = in.metallic;
    m.pbrMetallicRoughness.roughnessFactor = in.roughness;
    if (in.emissive != std::array<double, 3>{0, 0, 0}) m.emissiveFactor.assign(in.emissive.begin(), in.emissive.end());
    m.alphaMode = in.alpha_mode;
    m.alphaCutoff = in.alpha_cutoff;
    if (in.base_color_texture) {
        m.pbrMetallicRoughness.baseColorTexture.index = b.encoded_texture(in.name.c_str(), *in.base_color_texture);
        m.pbrMetallicRoughness.baseColorTexture.texCoord = 0;
    }
    return index;
}

// The feathers' vane texture over the card's UVs: x is u (root 0 to tip 1
// along the shaft), y is v (0 to 1 across the vanes, the shaft at 0.5). The
// vane is |v - 0.5| < 0.5 sin(pi u)^0.6, a rounded outline over the kite
// card, opaque inside, transparent outside (a one-pixel ramp at the edge);
// near-white so the material's colour shows, with soft slanted barbs and a
// darker shaft that runs from the root to near the tip.
uint32_t crc32(const unsigned char* p, size_t n, uint32_t crc = 0) {
    crc = ~crc;
    for (size_t i = 0; i < n; ++i) {
        crc ^= p[i];
        for (int k = 0; k < 8; ++k) crc = (crc >> 1) ^ (0xEDB88320u & (0u - (crc & 1u)));
    }
    return ~crc;
}

void put_u32(std::vector<unsigned char>& out, uint32_t v) {
    for (int shift = 24; shift >= 0; shift -= 8) out.push_back(static_cast<unsigned char>(v >> shift));
}

void png_chunk(std::vector<unsigned char>& out, const char* type, const std::vector<unsigned char>& data) {
    put_u32(out, static_cast<uint32_t>(data.size()));
    const size_t start = out.size();
    out.insert(out.end(), type, type + 4);
    out.insert(out.end(), data.begin(), data.end());
    put_u32(out, crc32(out.data() + start, out.size() - start));
}

// An RGBA8 image as PNG bytes: every row unfiltered, in stored
// (uncompressed) deflate blocks; small images only (a few tens of KiB).
std::vector<unsigned char> encode_png(const std::vector<unsigned char>& rgba, uint32_t width, uint32_t height) {
    std::vector<unsigned char> raw;
    raw.reserve((4 * size_t{width} + 1) * height);
    for (uint32_t y = 0; y < height; ++y) {
        raw.push_back(0);  // filter: none
        const auto row = rgba.begin() + static_cast<long>(4 * size_t{width} * y);
        raw.insert(raw.end(), row, row + static_cast<long>(4 * size_t{width}));
    }
    std::vector<unsigned char> z{0x78, 0x01};  // zlib header: deflate, 32 KiB window
    for (size_t at = 0; at < raw.size() || at == 0; at += 65535) {
        const size_t n = std::min<size_t>(65535, raw.size() - at);
        z.push_back(at + n == raw.size() ? 1 : 0);  // final block?
        z.insert(z.end(), {static_cast<unsigned char>(n), static_cast<unsigned char>(n >> 8), static_cast<unsigned char>(~n),
                           static_cast<unsigned char>(~n >> 8)});
        z.insert(z.end(), raw.begin() + static_cast<long>(at), raw.begin() + static_cast<long>(at + n));
        if (raw.empty()) break;
    }
    uint32_t a = 1, b = 0;  // Adler-32
    for (unsigned char c : raw) a = (a + c) % 65521, b = (b + a) % 65521;
    put_u32(z, (b << 16) | a);
    std::vector<unsigned char> png{0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
    std::vector<unsigned char> header;
    put_u32(header, width);
    put_u32(header, height);
    header.insert(header.end(), {8, 6, 0, 0, 0});  // 8-bit RGBA, deflate, no filter method, no interlace
    png_chunk(png, "IHDR", header);
    png_chunk(png, "IDAT", z);
    png_chunk(png, "IEND", {});
    return png;
}

constexpr double kVaneHalfWidth = 0.36;  // largest |v - 0.5| of the vane
constexpr double kVaneEnd = 0.9;         // u where the vane's rounded tip ends

std::vector<unsigned char> vane_texture(int width, int height) {
    std::vector<unsigned char> rgba(static_cast<size_t>(width) * static_cast<size_t>(height) * 4);
    const double pi = std::acos(-1.0);
    for (int y = 0; y < height; ++y) {
        for (int x = 0; x < width; ++x) {
            const double u = (x + 0.5) / width, v = (y + 0.5) / height;
            const double across = std::fabs(v - 0.5);
            const double half = kVaneHalfWidth * std::pow(std::sin(pi * std::min(u / kVaneEnd, 1.0)), 0.6);
            const bool shaft = across < 1.5 / height && u < 0.97;
            double alpha = std::clamp((half - across) * height + 0.5, 0.0, 1.0);
            // Barbs slant from the shaft towards the tip.
            const double barb = 0.5 + 0.5 * std::cos(2 * pi * (24 * u - 6 * across));
            double shade = (0.82 + 0.18 * barb) * (1.0 - 0.25 * across / std::max(half, 1e-6) * (across < half));
            if (shaft) alpha = 1.0, shade = 0.45;
            unsigned char* p = &rgba[(static_cast<size_t>(y) * static_cast<size_t>(width) + static_cast<size_t>(x)) * 4];
            const auto byte = [](double c) { return static_cast<unsigned char>(std::lround(std::clamp(c, 0.0, 1.0) * 255)); };
            p[0] = p[1] = p[2] = byte(shade);
            p[3] = byte(alpha);
        }
    }
    return rgba;
}

// The default feather material: double-sided, alpha-masked by the vane
// texture (a PNG in the buffer), whose near-white colour a brown factor tints.
int feather_material(GlbBuilder& b) {
    constexpr int kWidth = 128, kHeight = 64;
    EncodedTexture png;
    png.bytes = encode_png(vane_texture(kWidth, kHeight), kWidth, kHeight);
    png.mime_type = "image/png";
    png.mag_filter = TINYGLTF_TEXTURE_FILTER_LINEAR;
    png.min_filter = TINYGLTF_TEXTURE_FILTER_LINEAR_MIPMAP_LINEAR;
    png.wrap_s = png.wrap_t = TINYGLTF_TEXTURE_WRAP_CLAMP_TO_EDGE;
    const int texture = b.encoded_texture("feather_vane", png);
    const int index = b.material("feathers", {0.45, 0.32, 0.2, 1.0}, true);
    tinygltf::Material& m = b.model().materials[static_cast<size_t>(index)];
    m.pbrMetallicRoughness.baseColorTexture.index = texture;
    m.pbrMetallicRoughness.baseColorTexture.texCoord = 0;
    m.alphaMode = "MASK";
    m.alphaCutoff = 0.5;
    return index;
}

// The vertex attributes of one animated mesh: the rest pose and, per
// frame, the positions (and normals, when given) its morph targets reach.
struct AnimatedAttributes {
    const std::vector<float>& rest;
    const std::vector<std::vector<float>>& frames;
    const std::vector<float>* normals = nullptr;  // at rest
    const std::vector<std::vector<float>>* normal_frames = nullptr;
    const std::vector<float>* uvs = nullptr;
    const std::vector<float>* ids = nullptr;
};

std::vector<float> difference(const std::vector<float>& a, const std::vector<float>& b) {
    std::vector<float> d(a.size());
    for (size_t i = 0; i < a.size(); ++i) d[i] = a[i] - b[i];
    return d;
}

// A node showing the rest pose, with one morph target (a displacement) per frame.
int add_animated_mesh(GlbBuilder& b, const char* name, const AnimatedAttributes& a, const std::vector<uint32_t>& indices, int material) {
    tinygltf::Primitive prim;
    prim.mode = TINYGLTF_MODE_TRIANGLES;
    prim.material = material;
    prim.attributes["POSITION"] = b.positions(a.rest);
    if (a.normals) prim.attributes["NORMAL"] = b.vectors(*a.normals, TINYGLTF_TYPE_VEC3, 3);
    if (a.uvs) prim.attributes["TEXCOORD_0"] = b.vectors(*a.uvs, TINYGLTF_TYPE_VEC2, 2);
    if (a.ids) prim.attributes["_FEATHER_ID"] = b.scalars(*a.ids, false, true);
    prim.indices = b.indices(indices, a.rest.size() / 3);
    for (size_t k = 0; k < a.frames.size(); ++k) {
        std::map<std::string, int> target{{"POSITION", b.positions(difference(a.frames[k], a.rest))}};
        if (a.normals && a.normal_frames) target["NORMAL"] = b.vectors(difference((*a.normal_frames)[k], *a.normals), TINYGLTF_TYPE_VEC3, 3);
        prim.targets.push_back(std::move(target));
    }
    tinygltf::Mesh mesh;
    mesh.name = name;
    mesh.primitives.push_back(std::move(prim));
    mesh.weights.assign(a.frames.size(), 0.0);
    tinygltf::Model& m = b.model();
    m.meshes.push_back(std::move(mesh));
    tinygltf::Node node;
    node.name = name;
    node.mesh = static_cast<int>(m.meshes.size() - 1);
    m.nodes.push_back(std::move(node));
    return static_cast<int>(m.nodes.size() - 1);
}

// Frame k shows target k alone: STEP keys with one-hot weights.
void add_frame_switch(GlbBuilder& b, const std::vector<double>& times, const std::vector<int>& nodes) {
    const size_t n = times.size();
    std::vector<float> input(n), output(n * n, 0.0f);
    for (size_t k = 0; k < n; ++k) {
        input[k] = static_cast<float>(times[k] - times.front());
        output[k * n + k] = 1.0f;
    }
    tinygltf::AnimationSampler sampler;
    sampler.input = b.scalars(input, true);
    sampler.output = b.scalars(output, false);
    sampler.interpolation = "STEP";
    tinygltf::Animation anim;
    anim.name = "plumage";
    anim.samplers.push_back(sampler);
    for (int node : nodes) {
        tinygltf::AnimationChannel c;
        c.sampler = 0;
        c.target_node = node;
        c.target_path = "weights";
        anim.channels.push_back(c);
    }
    b.model().animations.push_back(std::move(anim));
}

// Texture `index` of `model` when its image is PNG or JPEG bytes in a buffer view.
std::optional<EncodedTexture> encoded_texture(const tinygltf::Model& model, int index) {
    if (index < 0 || static_cast<size_t>(index) >= model.textures.size()) return std::nullopt;
    const tinygltf::Texture& t = model.textures[static_cast<size_t>(index)];
    if (t.source < 0 || static_cast<size_t>(t.source) >= model.images.size()) return std::nullopt;
    const tinygltf::Image& image = model.images[static_cast<size_t>(t.source)];
    if (image.mimeType != "image/png" && image.mimeType != "image/jpeg") return std::nullopt;
    if (image.bufferView < 0 || static_cast<size_t>(image.bufferView) >= model.bufferViews.size()) return std::nullopt;
    const tinygltf::BufferView& v = model.bufferViews[static_cast<size_t>(image.bufferView)];
    if (v.buffer < 0 || static_cast<size_t>(v.buffer) >= model.buffers.size()) return std::nullopt;
    const std::vector<unsigned char>& data = model.buffers[static_cast<size_t>(v.buffer)].data;
    if (v.byteLength == 0 || v.byteOffset > data.size() || v.byteLength > data.size() - v.byteOffset) return std::nullopt;
    EncodedTexture out;
    out.bytes.assign(data.begin() + static_cast<long>(v.byteOffset), data.begin() + static_cast<long>(v.byteOffset + v.byteLength));
    out.mime_type = image.mimeType;
    if (t.sampler >= 0 && static_cast<size_t>(t.sampler) < model.samplers.size()) {
        const tinygltf::Sampler& s = model.samplers[static_cast<size_t>(t.sampler)];
        out.mag_filter = s.magFilter, out.min_filter = s.minFilter, out.wrap_s = s.wrapS, out.wrap_t = s.wrapT;
    }
    return out;
}

}  // namespace

std::optional<BodyMaterial> input_material(const tinygltf::Model& model, int mesh_index) {
    if (mesh_index < 0 || static_cast<size_t>(mesh_index) >= model.meshes.size()) return std::nullopt;
    // The triangle primitive with a material and the most vertex references (indices, else vertices).
    const tinygltf::Primitive* largest = nullptr;
    size_t most = 0;
    for (const tinygltf::Primitive& p : model.meshes[static_cast<size_t>(mesh_index)].primitives) {
        const bool triangles = p.mode == -1 || p.mode == TINYGLTF_MODE_TRIANGLES || p.mode == TINYGLTF_MODE_TRIANGLE_STRIP ||
                               p.mode == TINYGLTF_MODE_TRIANGLE_FAN;
        if (!triangles || p.material < 0) continue;
        const auto position = p.attributes.find("POSITION");
        const int acc = p.indices >= 0 ? p.indices : position != p.attributes.end() ? position->second : -1;
        const size_t n = acc >= 0 && static_cast<size_t>(acc) < model.accessors.size() ? model.accessors[static_cast<size_t>(acc)].count : 0;
        if (largest == nullptr || n > most) largest = &p, most = n;
    }
    if (largest == nullptr) return std::nullopt;
    const tinygltf::Primitive& p = *largest;
    if (static_cast<size_t>(p.material) >= model.materials.size()) return std::nullopt;
    const tinygltf::Material& m = model.materials[static_cast<size_t>(p.material)];
    const tinygltf::PbrMetallicRoughness& pbr = m.pbrMetallicRoughness;
    BodyMaterial out;
    if (!m.name.empty()) out.name = m.name;
    if (pbr.baseColorFactor.size() != 4 || !std::all_of(pbr.baseColorFactor.begin(), pbr.baseColorFactor.end(), in_unit)) return std::nullopt;
    // A base colour texture that cannot be carried: its factor alone
    // (white by default) would not be the body's colour, so the host's stays.
    if (pbr.baseColorTexture.index >= 0) {
        out.base_color_texture = encoded_texture(model, pbr.baseColorTexture.index);
        out.base_color_uv_set = pbr.baseColorTexture.texCoord;
    }
    if (pbr.baseColorTexture.index < 0 || out.base_color_texture) std::copy_n(pbr.baseColorFactor.begin(), 4, out.base_color.begin());
    if (!in_unit(pbr.metallicFactor) || !in_unit(pbr.roughnessFactor)) return std::nullopt;
    out.metallic = pbr.metallicFactor;
    out.roughness = pbr.roughnessFactor;
    if (!m.emissiveFactor.empty()) {
        if (m.emissiveFactor.size() != 3 || !std::all_of(m.emissiveFactor.begin(), m.emissiveFactor.end(), in_unit)) return std::nullopt;
        std::copy_n(m.emissiveFactor.begin(), 3, out.emissive.begin());
    }
    out.double_sided = m.doubleSided;
    if (m.alphaMode != "OPAQUE" && m.alphaMode != "MASK" && m.alphaMode != "BLEND") return std::nullopt;
    if (!std::isfinite(m.alphaCutoff) || m.alphaCutoff < 0) return std::nullopt;
    out.alpha_mode = m.alphaMode;
    out.alpha_cutoff = m.alphaCutoff;
    return out;
}

AnimationRecorder::AnimationRecorder(std::vector<float> body_rest, std::vector<uint32_t> body_indices, const std::vector<PlumageFeather>& feathers,
                                     FeatherMeshData feather_mesh)
    : body_rest_(std::move(body_rest)), body_indices_(std::move(body_indices)), feather_rest_(std::move(feather_mesh)) {
    size_t first = 0;
    for (size_t i = 0; i < feather_rest_.vertex_counts.size(); ++i) {
        first_vertex_.push_back(first);
        first += feather_rest_.vertex_counts[i];
        if (i < feathers.size()) slot_of_id_.emplace(feathers[i].id, i);
        rest_triangle_.push_back(i < feathers.size() ? feathers[i].triangle : UINT32_MAX);
    }
}

std::pair<std::vector<float>, std::vector<float>> AnimationRecorder::arrange_feathers(const std::vector<PlumageFeather>& feathers,
                                                                                      const FeatherMeshData& mesh) {
    // A feather missing from this frame keeps its last pose.
    std::vector<float> positions = feather_frames_.empty() ? feather_rest_.positions : feather_frames_.back();
    std::vector<float> normals = normal_frames_.empty() ? feather_rest_.normals : normal_frames_.back();
    size_t first = 0;
    for (size_t i = 0; i < mesh.vertex_counts.size(); ++i) {
        const size_t count = mesh.vertex_counts[i];
        const auto slot = i < feathers.size() ? slot_of_id_.find(feathers[i].id) : slot_of_id_.end();
        if (slot == slot_of_id_.end() || feather_rest_.vertex_counts[slot->second] != count) {
            ++untracked_;
        } else {
            const size_t to = 3 * first_vertex_[slot->second], from = 3 * first;
            std::copy_n(mesh.positions.begin() + static_cast<long>(from), 3 * count, positions.begin() + static_cast<long>(to));
            std::copy_n(mesh.normals.begin() + static_cast<long>(from), 3 * count, normals.begin() + static_cast<long>(to));
        }
        first += count;
    }
    return {std::move(positions), std::move(normals)};
}

void AnimationRecorder::add_frame(double seconds, const std::vector<float>& body, const std::vector<PlumageFeather>& feathers,
                                  const FeatherMeshData& feather_mesh) {
    times_.push_back(seconds);
    body_frames_.push_back(body);
    auto [positions, normals] = arrange_feathers(feathers, feather_mesh);
    feather_frames_.push_back(std::move(positions));
    normal_frames_.push_back(std::move(normals));
}

namespace {

// `material` with its base colour texture only when it has a UV per body vertex.
BodyMaterial usable_material(BodyMaterial material, size_t body_vertices) {
    if (material.base_color_texture && !(material.uvs.size() / 2 == body_vertices && material.uvs.size() % 2 == 0)) {
        material.base_color_texture.reset();  // no UVs for it: the host's grey
        material.base_color = BodyMaterial{}.base_color;
    }
    return material;
}

// xyz (or uv) values `first .. first + count` of each frame.
std::vector<std::vector<float>> slice_frames(const std::vector<std::vector<float>>& frames, size_t first, size_t count) {
    std::vector<std::vector<float>> out;
    for (const std::vector<float>& f : frames) out.emplace_back(f.begin() + static_cast<long>(first), f.begin() + static_cast<long>(first + count));
    return out;
}

}  // namespace

void AnimationRecorder::write_glb(const std::string& path) const {
    GlbBuilder b;
    std::vector<int> nodes;
    if (parts_.empty()) {
        AnimatedAttributes body{body_rest_, body_frames_};
        const BodyMaterial material = usable_material(body_material_, body_rest_.size() / 3);
        if (material.base_color_texture) body.uvs = &material.uvs;
        nodes.push_back(add_animated_mesh(b, "body", body, body_indices_, body_material(b, material)));
        if (!feather_rest_.positions.empty()) {
            std::vector<float> ids;
            ids.reserve(feather_rest_.positions.size() / 3);
            for (size_t f = 0; f < feather_rest_.vertex_counts.size(); ++f) ids.insert(ids.end(), feather_rest_.vertex_counts[f], static_cast<float>(f));
            const AnimatedAttributes feathers{feather_rest_.positions, feather_frames_, &feather_rest_.normals, &normal_frames_, &feather_rest_.uvs, &ids};
            nodes.push_back(add_animated_mesh(b, "feathers", feathers, feather_rest_.indices, feather_material(b)));
        }
    }
    int feathers_material = -1;
    for (size_t p = 0; p < parts_.size(); ++p) {
        const MeshPart& part = parts_[p];
        // The body: its vertices and triangles of the union, renumbered from 0.
        const std::vector<float> rest(body_rest_.begin() + static_cast<long>(3 * part.first_vertex),
                                      body_rest_.begin() + static_cast<long>(3 * (part.first_vertex + part.vertex_count)));
        const std::vector<std::vector<float>> frames = slice_frames(body_frames_, 3 * part.first_vertex, 3 * part.vertex_count);
        std::vector<uint32_t> indices;
        for (size_t i = 3 * part.first_triangle; i < 3 * (part.first_triangle + part.triangle_count); ++i) {
            indices.push_back(static_cast<uint32_t>(body_indices_[i] - part.first_vertex));
        }
        AnimatedAttributes body{rest, frames};
        const BodyMaterial material = usable_material(p < part_materials_.size() ? part_materials_[p] : BodyMaterial{}, part.vertex_count);
        if (material.base_color_texture) body.uvs = &material.uvs;
        nodes.push_back(add_animated_mesh(b, part.name.c_str(), body, indices, body_material(b, material)));

        // Its feathers: those rooted on its triangles, keeping their ids.
        std::vector<float> positions, normals, uvs, ids;
        std::vector<uint32_t> feather_indices;
        std::vector<std::pair<size_t, size_t>> runs;  // (first vertex in the whole mesh, count)
        size_t first = 0;
        for (size_t f = 0; f < feather_rest_.vertex_counts.size(); ++f) {
            const size_t count = feather_rest_.vertex_counts[f], from = first_vertex_[f];
            first += count;
            if (rest_triangle_[f] < part.first_triangle || rest_triangle_[f] >= part.first_triangle + part.triangle_count) continue;
            runs.emplace_back(from, count);
            ids.insert(ids.end(), count, static_cast<float>(f));
        }
        if (runs.empty()) continue;
        std::vector<uint32_t> new_index(feather_rest_.positions.size() / 3, UINT32_MAX);
        for (const auto& [from, count] : runs) {
            for (size_t v = from; v < from + count; ++v) new_index[v] = static_cast<uint32_t>(positions.size() / 3 + v - from);
            positions.insert(positions.end(), feather_rest_.positions.begin() + static_cast<long>(3 * from), feather_rest_.positions.begin() + static_cast<long>(3 * (from + count)));
            normals.insert(normals.end(), feather_rest_.normals.begin() + static_cast<long>(3 * from), feather_rest_.normals.begin() + static_cast<long>(3 * (from + count)));
            uvs.insert(uvs.end(), feather_rest_.uvs.begin() + static_cast<long>(2 * from), feather_rest_.uvs.begin() + static_cast<long>(2 * (from + count)));
        }
        for (size_t t = 0; t + 2 < feather_rest_.indices.size(); t += 3) {
            const uint32_t a = new_index[feather_rest_.indices[t]];
            if (a == UINT32_MAX) continue;  // another mesh's feather (a feather's triangles stay within it)
            feather_indices.insert(feather_indices.end(), {a, new_index[feather_rest_.indices[t + 1]], new_index[feather_rest_.indices[t + 2]]});
        }
        const auto gather = [&](const std::vector<std::vector<float>>& all) {
            std::vector<std::vector<float>> out;
            for (const std::vector<float>& frame : all) {
                std::vector<float> f;
                f.reserve(positions.size());
                for (const auto& [from, count] : runs) f.insert(f.end(), frame.begin() + static_cast<long>(3 * from), frame.begin() + static_cast<long>(3 * (from + count)));
                out.push_back(std::move(f));
            }
            return out;
        };
        const std::vector<std::vector<float>> position_frames = gather(feather_frames_), normal_frames = gather(normal_frames_);
        const AnimatedAttributes feathers{positions, position_frames, &normals, &normal_frames, &uvs, &ids};
        if (feathers_material < 0) feathers_material = feather_material(b);
        nodes.push_back(add_animated_mesh(b, (part.name + " feathers").c_str(), feathers, feather_indices, feathers_material));
    }
    if (!times_.empty()) add_frame_switch(b, times_, nodes);
    tinygltf::Scene scene;
    scene.name = "plumage";
    scene.nodes = nodes;
    b.model().scenes.push_back(std::move(scene));
    b.model().defaultScene = 0;

    std::error_code ec;
    const std::filesystem::path parent = std::filesystem::path(path).parent_path();
    if (!parent.empty()) std::filesystem::create_directories(parent, ec);
    tinygltf::TinyGLTF writer;
    if (!writer.WriteGltfSceneToFile(&b.model(), path, true, true, false, true)) throw OutputError("cannot write " + path);
}

}  // namespace plumage_host
