// The .glb writer and the report, on synthetic feathers: the layout of the
// feather mesh, frames matched by feather id, and figures left out when the
// library has not computed them.
//   output_test CASE WORK_DIR
#include "gltf_writer.h"
#include "check.h"
#include "plumage_system.h"
#include "report.h"

#include <tiny_gltf.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <functional>
#include <map>
#include <optional>
#include <string>

using namespace plumage_host;
using json = nlohmann::ordered_json;

namespace {

using plumage_check::check;

std::string g_dir;

std::string path(const std::string& name) { return (std::filesystem::path(g_dir) / name).string(); }

const std::vector<float> kBody{0, 0, 0, 1, 0, 0, 0, 1, 0};
const std::vector<uint32_t> kBodyIndices{0, 1, 2};

std::vector<PlumageFeather> feathers(const std::vector<uint64_t>& ids) {
    std::vector<PlumageFeather> out(ids.size());
    for (size_t i = 0; i < ids.size(); ++i) out[i].id = ids[i];
    return out;
}

// `count` kites as the library's geometry copy-out gives them: per feather
// root, tip, left and right corners (4 vertices), triangles (root, tip,
// left) and (root, right, tip), feather f at x = 2f, lifted by `lift`.
FeatherMeshData kites(size_t count, float lift) {
    FeatherMeshData m;
    for (size_t f = 0; f < count; ++f) {
        const float x = static_cast<float>(f) * 2, y = lift;
        const float corners[4][3] = {{x, y, 0}, {x + 1, y, 0}, {x + 0.4f, y + 0.25f, 0}, {x + 0.4f, y - 0.25f, 0}};
        const float uvs[4][2] = {{0, 0.5f}, {1, 0.5f}, {0.4f, 1}, {0.4f, 0}};
        for (int c = 0; c < 4; ++c) {
            m.positions.insert(m.positions.end(), corners[c], corners[c] + 3);
            m.normals.insert(m.normals.end(), {0.0f, lift > 0 ? 0.6f : 0.0f, lift > 0 ? 0.8f : 1.0f});
            m.uvs.insert(m.uvs.end(), uvs[c], uvs[c] + 2);
        }
        const uint32_t b = static_cast<uint32_t>(4 * f);
        m.indices.insert(m.indices.end(), {b, b + 1, b + 2, b, b + 3, b + 1});
        m.vertex_counts.push_back(4);
        m.placed.push_back(1);
    }
    return m;
}

// The triangle corners of `m`, 9 floats per triangle.
std::vector<float> kite_corners(const FeatherMeshData& m) {
    std::vector<float> out;
    for (uint32_t i : m.indices) out.insert(out.end(), m.positions.begin() + 3 * i, m.positions.begin() + 3 * i + 3);
    return out;
}

// Feathers `keep` (in that order) of `m`.
FeatherMeshData pick(const FeatherMeshData& m, const std::vector<size_t>& keep) {
    FeatherMeshData out;
    for (size_t f : keep) {
        const long v = static_cast<long>(4 * f);
        out.positions.insert(out.positions.end(), m.positions.begin() + 3 * v, m.positions.begin() + 3 * v + 12);
        out.normals.insert(out.normals.end(), m.normals.begin() + 3 * v, m.normals.begin() + 3 * v + 12);
        out.uvs.insert(out.uvs.end(), m.uvs.begin() + 2 * v, m.uvs.begin() + 2 * v + 8);
        const uint32_t b = static_cast<uint32_t>(out.vertex_counts.size() * 4);
        out.indices.insert(out.indices.end(), {b, b + 1, b + 2, b, b + 3, b + 1});
        out.vertex_counts.push_back(4);
        out.placed.push_back(1);
    }
    return out;
}

tinygltf::Model read_back(const std::string& file) {
    tinygltf::TinyGLTF loader;
    tinygltf::Model m;
    std::string err, warn;
    check(loader.LoadBinaryFromFile(&m, &err, &warn, file), "reads back: " + err, __LINE__);
    return m;
}

std::vector<float> floats(const tinygltf::Model& m, int accessor) {
    const tinygltf::Accessor& a = m.accessors[static_cast<size_t>(accessor)];
    const tinygltf::BufferView& v = m.bufferViews[static_cast<size_t>(a.bufferView)];
    std::vector<float> out(a.count * (a.type == TINYGLTF_TYPE_VEC3 ? 3 : a.type == TINYGLTF_TYPE_VEC2 ? 2 : 1));
    std::memcpy(out.data(), m.buffers[0].data.data() + v.byteOffset + a.byteOffset, out.size() * sizeof(float));
    return out;
}

std::vector<uint32_t> indices(const tinygltf::Model& m, int accessor) {
    const tinygltf::Accessor& a = m.accessors[static_cast<size_t>(accessor)];
    const unsigned char* p = m.buffers[0].data.data() + m.bufferViews[static_cast<size_t>(a.bufferView)].byteOffset + a.byteOffset;
    std::vector<uint32_t> out(a.count);
    for (size_t i = 0; i < a.count; ++i) {
        if (a.componentType == TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT) {
            uint16_t v;
            std::memcpy(&v, p + 2 * i, 2);
            out[i] = v;
        } else {
            std::memcpy(&out[i], p + 4 * i, 4);
        }
    }
    return out;
}

// The triangle corners of `mesh` at `frame` (-1: the base), as 9 floats per triangle.
std::vector<float> corners(const tinygltf::Model& m, size_t mesh, int frame) {
    const tinygltf::Primitive& p = m.meshes[mesh].primitives[0];
    std::vector<float> pos = floats(m, p.attributes.at("POSITION"));
    if (frame >= 0) {
        const std::vector<float> d = floats(m, p.targets[static_cast<size_t>(frame)].at("POSITION"));
        for (size_t i = 0; i < pos.size(); ++i) pos[i] += d[i];
    }
    std::vector<float> out;
    for (uint32_t i : indices(m, p.indices)) out.insert(out.end(), pos.begin() + 3 * i, pos.begin() + 3 * i + 3);
    return out;
}

bool near(const std::vector<float>& a, const std::vector<float>& b) {
    if (a.size() != b.size()) return false;
    for (size_t i = 0; i < a.size(); ++i) {
        if (std::fabs(a[i] - b[i]) > 1e-5f) return false;
    }
    return true;
}

size_t vertex_count(const tinygltf::Model& m, size_t mesh) {
    return m.accessors[static_cast<size_t>(m.meshes[mesh].primitives[0].attributes.at("POSITION"))].count;
}

// ---- the .glb -----------------------------------------------------------

void glb_layout_and_frames() {
    AnimationRecorder rec(kBody, kBodyIndices, feathers({10, 11, 12}), kites(3, 0));
    std::vector<float> moved = kBody;
    moved[1] = 0.5f;
    rec.add_frame(0.0, kBody, feathers({10, 11, 12}), kites(3, 1));
    rec.add_frame(0.5, moved, feathers({10, 11, 12}), kites(3, 2));
    rec.write_glb(path("four.glb"));
    const tinygltf::Model m = read_back(path("four.glb"));
    CHECK(m.meshes.size() == 2 && m.meshes[1].name == "feathers");
    CHECK(vertex_count(m, 1) == 12);  // the library's shared vertices
    CHECK(near(corners(m, 1, -1), kite_corners(kites(3, 0))));
    CHECK(near(corners(m, 1, 0), kite_corners(kites(3, 1))));
    CHECK(near(corners(m, 1, 1), kite_corners(kites(3, 2))));
    CHECK(near(corners(m, 0, 1), moved));
    CHECK(m.animations.size() == 1 && m.animations[0].samplers[0].interpolation == "STEP");
    const std::vector<float> times = floats(m, m.animations[0].samplers[0].input);
    const std::vector<float> weights = floats(m, m.animations[0].samplers[0].output);
    CHECK((times == std::vector<float>{0, 0.5f}));
    CHECK((weights == std::vector<float>{1, 0, 0, 1}));  // frame k shows target k alone
}

void glb_feather_attributes() {
    AnimationRecorder rec(kBody, kBodyIndices, feathers({10, 11, 12}), kites(3, 0));
    rec.add_frame(0.0, kBody, feathers({10, 11, 12}), kites(3, 1));
    rec.write_glb(path("attributes.glb"));
    const tinygltf::Model m = read_back(path("attributes.glb"));
    const tinygltf::Primitive& p = m.meshes[1].primitives[0];
    for (const char* key : {"POSITION", "NORMAL", "TEXCOORD_0", "_FEATHER_ID"}) check(p.attributes.count(key) == 1, key, __LINE__);
    CHECK(p.attributes.count("NORMAL") == 1 && m.meshes[0].primitives[0].attributes.count("NORMAL") == 0);
    const std::vector<float> normals = floats(m, p.attributes.at("NORMAL"));
    const std::vector<float> uvs = floats(m, p.attributes.at("TEXCOORD_0"));
    const std::vector<float> ids = floats(m, p.attributes.at("_FEATHER_ID"));
    CHECK(normals == kites(3, 0).normals && uvs == kites(3, 0).uvs);
    CHECK((ids == std::vector<float>{0, 0, 0, 0, 1, 1, 1, 1, 2, 2, 2, 2}));
    // Frame 0's target moves the normals too.
    CHECK(p.targets.size() == 1 && p.targets[0].count("NORMAL") == 1);
    std::vector<float> moved = floats(m, p.targets[0].at("NORMAL"));
    for (size_t i = 0; i < moved.size(); ++i) moved[i] += normals[i];
    CHECK(near(moved, kites(3, 1).normals));
}

void glb_feather_material() {
    // The feathers' material: double-sided, alpha-masked by a vane texture
    // the writer draws; read back, the image decodes to its size, clear
    // outside the vane (a corner) and opaque on the shaft mid-card.
    AnimationRecorder rec(kBody, kBodyIndices, feathers({10, 11}), kites(2, 0));
    rec.write_glb(path("material.glb"));
    const tinygltf::Model m = read_back(path("material.glb"));
    const int index = m.meshes[1].primitives[0].material;
    CHECK(index >= 0 && static_cast<size_t>(index) < m.materials.size());
    if (index < 0 || static_cast<size_t>(index) >= m.materials.size()) return;
    const tinygltf::Material& mat = m.materials[static_cast<size_t>(index)];
    CHECK(mat.doubleSided && mat.alphaMode == "MASK" && mat.alphaCutoff > 0.3 && mat.alphaCutoff < 0.7);
    CHECK(m.meshes[0].primitives[0].material != index);  // the body's is another
    const int tex = mat.pbrMetallicRoughness.baseColorTexture.index;
    CHECK(tex >= 0 && static_cast<size_t>(tex) < m.textures.size() && mat.pbrMetallicRoughness.baseColorTexture.texCoord == 0);
    if (tex < 0 || static_cast<size_t>(tex) >= m.textures.size()) return;
    const int source = m.textures[static_cast<size_t>(tex)].source;
    CHECK(source >= 0 && static_cast<size_t>(source) < m.images.size());
    if (source < 0 || static_cast<size_t>(source) >= m.images.size()) return;
    const tinygltf::Image& img = m.images[static_cast<size_t>(source)];
    CHECK(img.width == 128 && img.height == 64 && img.component == 4 && img.bits == 8);
    CHECK(img.image.size() == 128u * 64u * 4u);
    if (img.image.size() != 128u * 64u * 4u) return;
    const auto alpha = [&](double u, double v) {
        const int x = std::min(127, static_cast<int>(u * 128)), y = std::min(63, static_cast<int>(v * 64));
        return img.image[(static_cast<size_t>(y) * 128 + static_cast<size_t>(x)) * 4 + 3];
    };
    CHECK(alpha(0, 0) == 0 && alpha(1, 1) == 0 && alpha(0, 1) == 0 && alpha(1, 0) == 0);  // corners: outside the vane
    CHECK(alpha(0.5, 0.5) == 255 && alpha(0.5, 0.3) == 255);                          // mid-card: the shaft and a vane
    const size_t mid = (32u * 128u + 64u) * 4u, vane = (20u * 128u + 64u) * 4u;
    CHECK(img.image[mid] < img.image[vane]);  // the shaft is darker than the vane
    const std::vector<double> brown{0.45, 0.32, 0.2, 1.0};
    CHECK(mat.pbrMetallicRoughness.baseColorFactor == brown);
}

void glb_body_material() {
    // Without an input material the body is the host's grey; with one, its factors and name.
    AnimationRecorder plain(kBody, kBodyIndices, feathers({1}), kites(1, 0));
    plain.write_glb(path("plain.glb"));
    const tinygltf::Model a = read_back(path("plain.glb"));
    const tinygltf::Material& grey = a.materials[static_cast<size_t>(a.meshes[0].primitives[0].material)];
    CHECK(grey.name == "body" && (grey.pbrMetallicRoughness.baseColorFactor == std::vector<double>{0.78, 0.72, 0.66, 1.0}));

    tinygltf::Model in;
    in.meshes.resize(1);
    tinygltf::Primitive points, small, tris;
    points.mode = TINYGLTF_MODE_POINTS;
    points.material = 0;  // not a triangle primitive: passed over
    small.material = 0;   // fewer triangles: passed over
    small.indices = 0;
    tris.material = 1;
    tris.indices = 1;
    in.accessors.resize(2);
    in.accessors[0].count = 3;
    in.accessors[1].count = 30;
    in.meshes[0].primitives = {points, small, tris};
    in.materials.resize(2);
    tinygltf::Material& skin = in.materials[1];
    skin.name = "skin";
    skin.pbrMetallicRoughness.baseColorFactor = {0.9, 0.4, 0.5, 1.0};
    skin.pbrMetallicRoughness.metallicFactor = 0.25;
    skin.pbrMetallicRoughness.roughnessFactor = 0.6;
    skin.emissiveFactor = {0.1, 0, 0};
    skin.doubleSided = true;
    const std::optional<BodyMaterial> got = input_material(in, 0);
    CHECK(got.has_value());
    if (!got) return;
    CHECK(got->name == "skin" && got->metallic == 0.25 && got->roughness == 0.6 && got->double_sided && got->alpha_mode == "OPAQUE");
    CHECK((got->base_color == std::array<double, 4>{0.9, 0.4, 0.5, 1.0}) && (got->emissive == std::array<double, 3>{0.1, 0, 0}));
    AnimationRecorder rec(kBody, kBodyIndices, feathers({1}), kites(1, 0));
    rec.set_body_material(*got);
    rec.write_glb(path("skin.glb"));
    const tinygltf::Model b = read_back(path("skin.glb"));
    const tinygltf::Material& out = b.materials[static_cast<size_t>(b.meshes[0].primitives[0].material)];
    CHECK(out.name == "skin" && out.doubleSided && out.pbrMetallicRoughness.baseColorFactor == skin.pbrMetallicRoughness.baseColorFactor);
    CHECK(out.pbrMetallicRoughness.metallicFactor == 0.25 && out.pbrMetallicRoughness.roughnessFactor == 0.6 && out.emissiveFactor == skin.emissiveFactor);

    // A textured base colour (not carried over) keeps the host's grey, and the other factors.
    skin.pbrMetallicRoughness.baseColorTexture.index = 0;
    const std::optional<BodyMaterial> textured = input_material(in, 0);
    CHECK(textured && (textured->base_color == BodyMaterial{}.base_color) && textured->roughness == 0.6);
    skin.pbrMetallicRoughness.baseColorTexture.index = -1;

    // No material, a dangling index, factors out of range, no such mesh: nothing.
    in.meshes[0].primitives[2].material = -1;
    CHECK(input_material(in, 0).has_value() && input_material(in, 0)->name == "body");  // the smaller one's (unnamed)
    in.meshes[0].primitives[1].material = -1;
    CHECK(!input_material(in, 0).has_value());
    in.meshes[0].primitives[2].material = 7;
    CHECK(!input_material(in, 0).has_value());
    in.meshes[0].primitives[2].material = 1;
    skin.pbrMetallicRoughness.baseColorFactor = {2, 0, 0, 1};
    CHECK(!input_material(in, 0).has_value() && !input_material(in, 1).has_value() && !input_material(in, -1).has_value());
}

// A 2x1 RGBA PNG: a red pixel, then a blue one.
const std::vector<unsigned char> kPng{
    0x89, 0x50, 0x4e, 0x47, 0x0d, 0x0a, 0x1a, 0x0a, 0x00, 0x00, 0x00, 0x0d, 0x49, 0x48, 0x44, 0x52, 0x00, 0x00, 0x00, 0x02,
    0x00, 0x00, 0x00, 0x01, 0x08, 0x06, 0x00, 0x00, 0x00, 0xf4, 0x22, 0x7f, 0x8a, 0x00, 0x00, 0x00, 0x0e, 0x49, 0x44, 0x41,
    0x54, 0x78, 0x9c, 0x63, 0xf8, 0xcf, 0xc0, 0x00, 0x42, 0xff, 0x01, 0x0f, 0xf9, 0x03, 0xfd, 0x85, 0x11, 0x99, 0x76, 0x00,
    0x00, 0x00, 0x00, 0x49, 0x45, 0x4e, 0x44, 0xae, 0x42, 0x60, 0x82};

void glb_body_texture() {
    // The input's base colour texture (a PNG in a buffer view) is carried
    // with its sampler, on the body's UVs written as TEXCOORD_0.
    tinygltf::Model in;
    in.buffers.resize(1);
    in.buffers[0].data.assign(8, 0);  // the image does not start the buffer
    in.buffers[0].data.insert(in.buffers[0].data.end(), kPng.begin(), kPng.end());
    tinygltf::BufferView view;
    view.buffer = 0;
    view.byteOffset = 8;
    view.byteLength = kPng.size();
    in.bufferViews.push_back(view);
    tinygltf::Image image;
    image.mimeType = "image/png";
    image.bufferView = 0;
    in.images.push_back(image);
    tinygltf::Sampler sampler;
    sampler.magFilter = TINYGLTF_TEXTURE_FILTER_NEAREST;
    sampler.wrapS = TINYGLTF_TEXTURE_WRAP_MIRRORED_REPEAT;
    in.samplers.push_back(sampler);
    tinygltf::Texture texture;
    texture.source = 0;
    texture.sampler = 0;
    in.textures.push_back(texture);
    tinygltf::Material skin;
    skin.name = "skin";
    skin.pbrMetallicRoughness.baseColorFactor = {1, 0.5, 1, 1};
    skin.pbrMetallicRoughness.baseColorTexture.index = 0;
    skin.pbrMetallicRoughness.baseColorTexture.texCoord = 1;
    in.materials.push_back(skin);
    in.meshes.resize(1);
    in.meshes[0].primitives.resize(1);
    in.meshes[0].primitives[0].material = 0;

    std::optional<BodyMaterial> got = input_material(in, 0);
    CHECK(got && got->base_color_texture && got->base_color_uv_set == 1);
    if (!got || !got->base_color_texture) return;
    CHECK(got->base_color_texture->bytes == kPng && got->base_color_texture->mime_type == "image/png");
    CHECK(got->base_color_texture->mag_filter == TINYGLTF_TEXTURE_FILTER_NEAREST && got->base_color_texture->wrap_s == TINYGLTF_TEXTURE_WRAP_MIRRORED_REPEAT);
    CHECK((got->base_color == std::array<double, 4>{1, 0.5, 1, 1}));  // carried with its texture, the factor too

    got->uvs = {0, 0, 1, 0, 0, 1};
    AnimationRecorder rec(kBody, kBodyIndices, feathers({1}), kites(1, 0));
    rec.set_body_material(*got);
    rec.write_glb(path("textured.glb"));
    const tinygltf::Model m = read_back(path("textured.glb"));
    const tinygltf::Primitive& body = m.meshes[0].primitives[0];
    CHECK(body.attributes.count("TEXCOORD_0") == 1);
    if (body.attributes.count("TEXCOORD_0") == 1) CHECK((floats(m, body.attributes.at("TEXCOORD_0")) == got->uvs));
    const tinygltf::Material& out = m.materials[static_cast<size_t>(body.material)];
    const tinygltf::TextureInfo& info = out.pbrMetallicRoughness.baseColorTexture;
    CHECK(out.name == "skin" && info.index >= 0 && info.texCoord == 0);
    if (info.index < 0) return;
    const tinygltf::Texture& t = m.textures[static_cast<size_t>(info.index)];
    const tinygltf::Image& decoded = m.images[static_cast<size_t>(t.source)];
    CHECK(decoded.width == 2 && decoded.height == 1 && decoded.image.size() == 8);
    if (decoded.image.size() == 8) CHECK(decoded.image[0] == 255 && decoded.image[2] == 0 && decoded.image[4] == 0 && decoded.image[6] == 255);
    CHECK(m.samplers[static_cast<size_t>(t.sampler)].magFilter == TINYGLTF_TEXTURE_FILTER_NEAREST);

    // Without UVs for every body vertex the texture is dropped: the host's grey, no TEXCOORD_0.
    got->uvs = {0, 0};
    AnimationRecorder bare(kBody, kBodyIndices, feathers({1}), kites(1, 0));
    bare.set_body_material(*got);
    bare.write_glb(path("untextured.glb"));
    const tinygltf::Model u = read_back(path("untextured.glb"));
    const tinygltf::Material& grey = u.materials[static_cast<size_t>(u.meshes[0].primitives[0].material)];
    CHECK(grey.pbrMetallicRoughness.baseColorTexture.index < 0 && u.meshes[0].primitives[0].attributes.count("TEXCOORD_0") == 0);
    const std::array<double, 4> host_grey = BodyMaterial{}.base_color;
    CHECK(grey.pbrMetallicRoughness.baseColorFactor == std::vector<double>(host_grey.begin(), host_grey.end()));

    // An image that is not a PNG or JPEG in a buffer view is not carried, nor one past its buffer.
    in.images[0].mimeType = "image/webp";
    got = input_material(in, 0);
    CHECK(got && !got->base_color_texture && (got->base_color == BodyMaterial{}.base_color));
    in.images[0].mimeType = "image/png";
    in.bufferViews[0].byteLength = 1000;
    got = input_material(in, 0);
    CHECK(got && !got->base_color_texture);
}

void glb_feathers_matched_by_id() {
    AnimationRecorder rec(kBody, kBodyIndices, feathers({7, 8, 9}), kites(3, 0));
    // Frame 0 lists the feathers in reverse, plus one the rest pose did not have.
    const FeatherMeshData lifted = kites(4, 1);
    rec.add_frame(0.0, kBody, feathers({9, 8, 7, 99}), pick(lifted, {2, 1, 0, 3}));
    // Frame 1 lacks feather 8: it keeps its last pose.
    rec.add_frame(1.0, kBody, feathers({7, 9}), pick(kites(3, 2), {0, 2}));
    CHECK(rec.untracked_feathers() == 1);
    rec.write_glb(path("by_id.glb"));
    const tinygltf::Model m = read_back(path("by_id.glb"));
    CHECK(near(corners(m, 1, 0), kite_corners(pick(lifted, {0, 1, 2}))));
    std::vector<float> expected = kite_corners(kites(3, 2));
    const std::vector<float> kept = kite_corners(pick(lifted, {1}));
    std::copy(kept.begin(), kept.end(), expected.begin() + 18);
    CHECK(near(corners(m, 1, 1), expected));
}

void glb_rest_only() {
    AnimationRecorder rec(kBody, kBodyIndices, feathers({1}), kites(1, 0));
    rec.write_glb(path("sub/dir/rest.glb"));  // parent directories are created
    const tinygltf::Model m = read_back(path("sub/dir/rest.glb"));
    CHECK(m.animations.empty() && m.meshes.size() == 2 && m.meshes[1].primitives[0].targets.empty());
    AnimationRecorder bare(kBody, kBodyIndices, {}, {});
    bare.write_glb(path("bare.glb"));
    CHECK(read_back(path("bare.glb")).meshes.size() == 1);  // no feathers, no feather mesh
}

// ---- the report ---------------------------------------------------------

Report subject() {
    Report r;
    PlumageConfig cfg;
    plumage_config_init(&cfg);
    r.set_subject("in.glb", "body", 3, 1, config_to_json(cfg));
    return r;
}

void report_leaves_out_missing_figures() {
    Report r = subject();
    r.set_sampling(std::nullopt);
    r.set_ordering(std::nullopt);
    r.set_static(std::nullopt, std::nullopt);
    r.add_frame(0, 0.0, 0.001, std::nullopt, std::nullopt);
    const json j = r.to_json();
    std::vector<std::string> keys;
    for (auto it = j.begin(); it != j.end(); ++it) keys.push_back(it.key());
    CHECK((keys == std::vector<std::string>{"schema", "input", "mesh", "vertices", "triangles", "feathers", "config", "frames", "summary", "timing"}));
    CHECK(j["frames"][0].size() == 3);  // index, time, step_seconds
    CHECK(j["summary"].size() == 2);    // frames, mean_step_seconds
    CHECK(j["config"]["theta_deg"] == 45.0 && j["config"]["mode"] == "incremental");
}

void report_partial_struct() {
    // An older library fills only the fields it knows: the rest is left out.
    Report r = subject();
    PlumageFrameStats s{};
    s.adjusted = 5;
    s.collision_tests_per_feather = 3;
    s.struct_size = static_cast<uint32_t>(offsetof(PlumageFrameStats, adjusted) + sizeof s.adjusted);
    PlumageValidation v{};
    v.intersecting_pairs = 2;
    v.body_penetrations = 1;
    v.coverage = 0.5;
    v.struct_size = static_cast<uint32_t>(offsetof(PlumageValidation, body_penetrations) + sizeof v.body_penetrations);
    r.add_frame(0, 0.0, 0.001, s, v);
    const json f = r.to_json()["frames"][0];
    CHECK(f["adjusted"] == 5 && !f.contains("collision_tests_per_feather") && !f.contains("priority_changes"));
    CHECK(f["intersecting_pairs"] == 2 && f["body_penetrations"] == 1 && !f.contains("coverage") && !f.contains("buried_probes"));
}

void report_summary() {
    Report r = subject();
    r.set_feathers(3);
    for (int k = 0; k < 2; ++k) {
        PlumageFrameStats s{};
        s.struct_size = sizeof s;
        s.adjusted = static_cast<uint64_t>(2 + 2 * k);
        PlumageValidation v{};
        v.struct_size = sizeof v;
        v.intersecting_pairs = static_cast<uint64_t>(1 + 4 * k);
        v.coverage = 0.9 - 0.1 * k;
        v.mean_pitch_deg = std::nan("");  // not JSON: left out
        v.probes = 100;
        v.buried_probes = static_cast<uint64_t>(k);
        v.tip_height_median = 0.1 + 0.05 * k;
        v.tip_height_p90 = 0.25 - 0.1 * k;
        v.bristle_percent = 1.5 * k;
        v.stack_efficiency = 1.75 - 0.5 * k;
        v.stack_depth_median = 2.0 + k;
        s.pops = static_cast<uint64_t>(3 * k);
        r.add_frame(static_cast<size_t>(k), k / 30.0, 0.002, s, v);
    }
    const json sum = r.to_json()["summary"];
    CHECK(sum["frames"] == 2 && sum["mean_adjusted"] == 3.0 && sum["max_intersecting_pairs"] == 5);
    CHECK(std::fabs(sum["min_coverage"].get<double>() - 0.8) < 1e-12 && std::fabs(sum["mean_step_seconds"].get<double>() - 0.002) < 1e-12);
    CHECK(!r.to_json()["frames"][0].contains("mean_pitch_deg"));
    CHECK(r.to_json()["frames"][1]["coverage_probes"] == 100 && r.to_json()["frames"][1]["buried_probes"] == 1);
    CHECK(std::fabs(sum["max_tip_height_median"].get<double>() - 0.15) < 1e-12 && std::fabs(sum["max_tip_height_p90"].get<double>() - 0.25) < 1e-12);
    CHECK(sum["max_bristle_percent"] == 1.5 && r.to_json()["frames"][0]["tip_height_p90"] == 0.25);
    CHECK(sum["max_stack_efficiency"] == 1.75 && r.to_json()["frames"][1]["stack_efficiency"] == 1.25 && r.to_json()["frames"][1]["stack_depth_median"] == 3.0);
    CHECK(r.to_json()["frames"][1]["pops"] == 3 && std::fabs(sum["max_pops_percent"].get<double>() - 100.0) < 1e-12);
    CHECK(tidy(0.1f) == 0.1 && tidy(0.6f) == 0.6);
}

void report_memory() {
    // Figures the platform gives are written, the others left out; a phase with none is left out whole.
    Report r = subject();
    MemoryUsage created;
    created.rss_kib = 2048;
    created.peak_rss_kib = 4096;
    r.set_memory("after_load", MemoryUsage{});
    r.set_memory("after_create", created);
    MemoryUsage stepped = created;
    stepped.heap_kib = 1000;
    r.add_frame(0, 0.0, 0.001, std::nullopt, std::nullopt, stepped);
    r.add_frame(1, 1 / 30.0, 0.001, std::nullopt, std::nullopt);
    const json j = r.to_json();
    CHECK(j["memory"].size() == 1 && j["memory"]["after_create"] == json({{"rss_kib", 2048}, {"peak_rss_kib", 4096}}));
    CHECK(j["frames"][0]["rss_kib"] == 2048 && j["frames"][0]["peak_rss_kib"] == 4096 && j["frames"][0]["heap_kib"] == 1000);
    CHECK(!j["frames"][1].contains("rss_kib") && !j["frames"][1].contains("heap_kib"));
    std::vector<std::string> keys;
    for (auto it = j.begin(); it != j.end(); ++it) keys.push_back(it.key());
    CHECK((keys == std::vector<std::string>{"schema", "input", "mesh", "vertices", "triangles", "feathers", "config", "memory", "frames", "summary",
                                            "timing"}));
    CHECK(memory_usage().rss_kib.has_value() == std::filesystem::exists("/proc/self/status"));
}

const std::map<std::string, std::function<void()>> kCases = {
    {"glb_layout_and_frames", glb_layout_and_frames},
    {"glb_feather_attributes", glb_feather_attributes},
    {"glb_feather_material", glb_feather_material},
    {"glb_body_material", glb_body_material},
    {"glb_body_texture", glb_body_texture},
    {"glb_feathers_matched_by_id", glb_feathers_matched_by_id},
    {"glb_rest_only", glb_rest_only},
    {"report_leaves_out_missing_figures", report_leaves_out_missing_figures},
    {"report_partial_struct", report_partial_struct},
    {"report_summary", report_summary},
    {"report_memory", report_memory},
};

}  // namespace

int main(int argc, char** argv) {
    if (argc != 3 || kCases.count(argv[1]) == 0) {
        std::fprintf(stderr, "usage: output_test CASE WORK_DIR\n");
        return 2;
    }
    g_dir = (std::filesystem::path(argv[2]) / argv[1]).string();
    std::filesystem::remove_all(g_dir);
    std::filesystem::create_directories(g_dir);
    try {
        kCases.at(argv[1])();
    } catch (const std::exception& e) {
        check(false, std::string("unexpected exception: ") + e.what(), __LINE__);
    }
    return plumage_check::finish(argv[1]);
}
