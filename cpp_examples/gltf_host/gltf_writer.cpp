#include "gltf_writer.h"

#include "errors.h"

#include <tiny_gltf.h>

#include <algorithm>
#include <array>
#include <cstring>
#include <filesystem>
#include <limits>
#include <optional>

namespace plumage_host {
namespace {

constexpr size_t kFeatherFloats = 18;  // two triangles of three xyz corners

// Which of a feather's six corners coincide: label[c] is the first corner equal to c.
using CornerPattern = std::array<uint8_t, 6>;

CornerPattern pattern_of(const float* corners) {
    CornerPattern label{};
    for (uint8_t c = 0; c < 6; ++c) {
        label[c] = c;
        for (uint8_t e = 0; e < c; ++e) {
            if (std::memcmp(corners + 3 * c, corners + 3 * e, 3 * sizeof(float)) == 0) {
                label[c] = label[e];
                break;
            }
        }
    }
    return label;
}

size_t distinct(const CornerPattern& p) {
    size_t n = 0;
    for (uint8_t c = 0; c < 6; ++c) n += p[c] == c;
    return n;
}

// Four vertices per feather (root, tip, two vane corners) when every feather
// of every pose shares the same pattern of four distinct corners; otherwise
// (degenerate feathers, corners that differ by rounding) six.
std::optional<CornerPattern> shared_pattern(const std::vector<const std::vector<float>*>& poses) {
    std::optional<CornerPattern> shared;
    for (const std::vector<float>* pose : poses) {
        for (size_t f = 0; f + kFeatherFloats <= pose->size(); f += kFeatherFloats) {
            const CornerPattern p = pattern_of(pose->data() + f);
            if (!shared) shared = p;
            if (p != *shared || distinct(p) != 4) return std::nullopt;
        }
    }
    return shared;
}

// The vertices one layout keeps per feather, in order.
std::vector<uint8_t> kept_corners(const std::optional<CornerPattern>& pattern) {
    std::vector<uint8_t> kept;
    for (uint8_t c = 0; c < 6; ++c) {
        if (!pattern || (*pattern)[c] == c) kept.push_back(c);
    }
    return kept;
}

std::vector<float> pick_corners(const std::vector<float>& feathers, const std::vector<uint8_t>& kept) {
    std::vector<float> out;
    out.reserve(feathers.size() / kFeatherFloats * kept.size() * 3);
    for (size_t f = 0; f + kFeatherFloats <= feathers.size(); f += kFeatherFloats) {
        for (uint8_t c : kept) out.insert(out.end(), feathers.begin() + static_cast<long>(f + 3 * c), feathers.begin() + static_cast<long>(f + 3 * c + 3));
    }
    return out;
}

std::vector<uint32_t> feather_indices(size_t feathers, const std::optional<CornerPattern>& pattern, const std::vector<uint8_t>& kept) {
    std::array<uint32_t, 6> local{};
    for (uint8_t c = 0; c < 6; ++c) {
        const uint8_t source = pattern ? (*pattern)[c] : c;
        local[c] = static_cast<uint32_t>(std::find(kept.begin(), kept.end(), source) - kept.begin());
    }
    std::vector<uint32_t> out;
    out.reserve(feathers * 6);
    for (size_t f = 0; f < feathers; ++f) {
        for (uint32_t l : local) out.push_back(static_cast<uint32_t>(f * kept.size()) + l);
    }
    return out;
}

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

    int scalars(const std::vector<float>& values, bool with_bounds) {
        std::vector<double> lo, hi;
        if (with_bounds && !values.empty()) {
            const auto [a, b] = std::minmax_element(values.begin(), values.end());
            lo = {*a}, hi = {*b};
        }
        return accessor(view(values.data(), values.size() * sizeof(float), 0), TINYGLTF_COMPONENT_TYPE_FLOAT, values.size(), TINYGLTF_TYPE_SCALAR, lo, hi);
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

// A node showing `rest`, with one morph target (a displacement) per frame.
int add_animated_mesh(GlbBuilder& b, const char* name, const std::vector<float>& rest, const std::vector<uint32_t>& indices,
                      const std::vector<std::vector<float>>& frames, int material) {
    tinygltf::Primitive prim;
    prim.mode = TINYGLTF_MODE_TRIANGLES;
    prim.material = material;
    prim.attributes["POSITION"] = b.positions(rest);
    prim.indices = b.indices(indices, rest.size() / 3);
    std::vector<float> delta(rest.size());
    for (const std::vector<float>& frame : frames) {
        for (size_t i = 0; i < rest.size(); ++i) delta[i] = frame[i] - rest[i];
        prim.targets.push_back({{"POSITION", b.positions(delta)}});
    }
    tinygltf::Mesh mesh;
    mesh.name = name;
    mesh.primitives.push_back(std::move(prim));
    mesh.weights.assign(frames.size(), 0.0);
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

}  // namespace

AnimationRecorder::AnimationRecorder(std::vector<float> body_rest, std::vector<uint32_t> body_indices, const std::vector<PlumageFeather>& feathers,
                                     std::vector<float> feather_triangles)
    : body_rest_(std::move(body_rest)), body_indices_(std::move(body_indices)) {
    const size_t n = std::min(feathers.size(), feather_triangles.size() / kFeatherFloats);
    feather_triangles.resize(n * kFeatherFloats);
    feather_rest_ = std::move(feather_triangles);
    for (size_t i = 0; i < n; ++i) slot_of_id_.emplace(feathers[i].id, i);
}

std::vector<float> AnimationRecorder::arrange_feathers(const std::vector<PlumageFeather>& feathers, const std::vector<float>& triangles,
                                                       const std::vector<float>& previous) {
    std::vector<float> out = previous;  // a feather missing from this frame keeps its last pose
    const size_t n = std::min(feathers.size(), triangles.size() / kFeatherFloats);
    for (size_t i = 0; i < n; ++i) {
        const auto slot = slot_of_id_.find(feathers[i].id);
        if (slot == slot_of_id_.end()) {
            ++untracked_;
            continue;
        }
        std::copy_n(triangles.begin() + static_cast<long>(i * kFeatherFloats), kFeatherFloats, out.begin() + static_cast<long>(slot->second * kFeatherFloats));
    }
    return out;
}

void AnimationRecorder::add_frame(double seconds, const std::vector<float>& body, const std::vector<PlumageFeather>& feathers,
                                  const std::vector<float>& feather_triangles) {
    times_.push_back(seconds);
    body_frames_.push_back(body);
    feather_frames_.push_back(arrange_feathers(feathers, feather_triangles, feather_frames_.empty() ? feather_rest_ : feather_frames_.back()));
}

void AnimationRecorder::write_glb(const std::string& path) const {
    GlbBuilder b;
    std::vector<int> nodes{add_animated_mesh(b, "body", body_rest_, body_indices_, body_frames_, b.material("body", {0.78, 0.72, 0.66, 1.0}, false))};
    if (!feather_rest_.empty()) {
        std::vector<const std::vector<float>*> poses{&feather_rest_};
        for (const std::vector<float>& f : feather_frames_) poses.push_back(&f);
        const std::optional<CornerPattern> pattern = shared_pattern(poses);
        const std::vector<uint8_t> kept = kept_corners(pattern);
        std::vector<std::vector<float>> frames;
        for (const std::vector<float>& f : feather_frames_) frames.push_back(pick_corners(f, kept));
        const std::vector<uint32_t> indices = feather_indices(feather_rest_.size() / kFeatherFloats, pattern, kept);
        nodes.push_back(add_animated_mesh(b, "feathers", pick_corners(feather_rest_, kept), indices, frames,
                                          b.material("feathers", {0.45, 0.32, 0.2, 1.0}, true)));
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
