#include "gltf_scene.h"

#include "accessor.h"
#include "errors.h"

#include <tiny_gltf.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace plumage_host {
namespace {

bool is_triangle_mode(int mode) {
    return mode == -1 || mode == TINYGLTF_MODE_TRIANGLES || mode == TINYGLTF_MODE_TRIANGLE_STRIP || mode == TINYGLTF_MODE_TRIANGLE_FAN;
}

int attribute(const std::map<std::string, int>& attributes, const std::string& name) {
    const auto it = attributes.find(name);
    return it == attributes.end() ? -1 : it->second;
}

int attribute(const tinygltf::Primitive& p, const std::string& name) { return attribute(p.attributes, name); }

const tinygltf::Accessor& accessor_at(const tinygltf::Model& model, int index, const std::string& what) {
    if (index < 0 || static_cast<size_t>(index) >= model.accessors.size()) throw InputError(what + ": accessor " + std::to_string(index) + " does not exist");
    return model.accessors[static_cast<size_t>(index)];
}

size_t accessor_count(const tinygltf::Model& model, int index) {
    return index >= 0 && static_cast<size_t>(index) < model.accessors.size() ? model.accessors[static_cast<size_t>(index)].count : 0;
}

// Triangles a primitive contributes (for choosing the default mesh).
size_t primitive_triangles(const tinygltf::Model& model, const tinygltf::Primitive& p) {
    if (!is_triangle_mode(p.mode)) return 0;
    const size_t n = p.indices >= 0 ? accessor_count(model, p.indices) : accessor_count(model, attribute(p, "POSITION"));
    if (p.mode == TINYGLTF_MODE_TRIANGLE_STRIP || p.mode == TINYGLTF_MODE_TRIANGLE_FAN) return n >= 3 ? n - 2 : 0;
    return n / 3;
}

size_t mesh_triangles(const tinygltf::Model& model, const tinygltf::Mesh& mesh) {
    size_t n = 0;
    for (const tinygltf::Primitive& p : mesh.primitives) n += primitive_triangles(model, p);
    return n;
}

bool mesh_is_animated(const tinygltf::Model& model, int mesh) {
    const tinygltf::Mesh& m = model.meshes[static_cast<size_t>(mesh)];
    for (const tinygltf::Primitive& p : m.primitives) {
        if (!p.targets.empty()) return true;
    }
    for (const tinygltf::Node& node : model.nodes) {
        if (node.mesh == mesh && node.skin >= 0) return true;
    }
    return false;
}

std::string list_names(const std::vector<std::string>& names) {
    std::string out;
    for (size_t i = 0; i < names.size(); ++i) {
        out += (i ? ", " : "") + std::to_string(i) + ":\"" + names[i] + "\"";
    }
    return out.empty() ? "none" : out;
}

// Finds `request` among `names` by exact name, then as a number.
int find_by_name_or_index(const std::vector<std::string>& names, const std::string& request) {
    for (size_t i = 0; i < names.size(); ++i) {
        if (names[i] == request) return static_cast<int>(i);
    }
    if (!request.empty() && request.size() < 10 && std::all_of(request.begin(), request.end(), [](char c) { return c >= '0' && c <= '9'; })) {
        const size_t i = std::stoul(request);
        if (i < names.size()) return static_cast<int>(i);
    }
    return -1;
}

int choose_mesh(const tinygltf::Model& model, const std::string& request) {
    std::vector<std::string> names;
    for (const tinygltf::Mesh& m : model.meshes) names.push_back(m.name);
    if (!request.empty()) {
        const int found = find_by_name_or_index(names, request);
        if (found < 0) throw UsageError("--mesh " + request + ": no such mesh (meshes: " + list_names(names) + ")");
        if (mesh_triangles(model, model.meshes[static_cast<size_t>(found)]) == 0) throw InputError("mesh " + request + " has no triangles");
        return found;
    }
    int best = -1, best_animated = -1;
    size_t most = 0, most_animated = 0;
    for (size_t i = 0; i < model.meshes.size(); ++i) {
        const size_t n = mesh_triangles(model, model.meshes[i]);
        if (n > most) most = n, best = static_cast<int>(i);
        if (n > most_animated && mesh_is_animated(model, static_cast<int>(i))) most_animated = n, best_animated = static_cast<int>(i);
    }
    if (best < 0) throw InputError("the file holds no triangle mesh");
    return best_animated >= 0 ? best_animated : best;
}

// The node that shows `mesh`: the first in the default scene, else any.
int find_instance_node(const tinygltf::Model& model, int mesh, const std::vector<size_t>& order) {
    const int scene = model.defaultScene >= 0 ? model.defaultScene : (model.scenes.empty() ? -1 : 0);
    if (scene >= 0 && static_cast<size_t>(scene) < model.scenes.size()) {
        std::vector<int> stack(model.scenes[static_cast<size_t>(scene)].nodes.rbegin(), model.scenes[static_cast<size_t>(scene)].nodes.rend());
        while (!stack.empty()) {
            const int n = stack.back();
            stack.pop_back();
            if (n < 0 || static_cast<size_t>(n) >= model.nodes.size()) continue;
            const tinygltf::Node& node = model.nodes[static_cast<size_t>(n)];
            if (node.mesh == mesh) return n;
            stack.insert(stack.end(), node.children.rbegin(), node.children.rend());
        }
    }
    for (size_t n : order) {
        if (model.nodes[n].mesh == mesh) return static_cast<int>(n);
    }
    return -1;
}

// Strips and fans as plain triangle lists (glTF 2.0, 3.7.2.1).
std::vector<uint32_t> triangle_list(int mode, const std::vector<uint32_t>& v, const std::string& what) {
    if (mode != TINYGLTF_MODE_TRIANGLE_STRIP && mode != TINYGLTF_MODE_TRIANGLE_FAN) {
        if (v.size() % 3 != 0) throw InputError(what + ": index count is not a multiple of 3");
        return v;
    }
    std::vector<uint32_t> out;
    for (size_t i = 0; i + 2 < v.size(); ++i) {
        if (mode == TINYGLTF_MODE_TRIANGLE_FAN) out.insert(out.end(), {v[i + 1], v[i + 2], v[0]});
        else if (i % 2 == 0) out.insert(out.end(), {v[i], v[i + 1], v[i + 2]});
        else out.insert(out.end(), {v[i + 1], v[i], v[i + 2]});
    }
    return out;
}

Mat4 read_matrix(const std::vector<double>& m) {
    Mat4 r;
    std::copy(m.begin(), m.end(), r.m.begin());
    return r;
}

// A double as a float; beyond float's range it is an infinity (a plain
// cast of such a value is undefined behaviour).
float to_float(double x) {
    constexpr double kMax = static_cast<double>(std::numeric_limits<float>::max());
    if (x > kMax) return std::numeric_limits<float>::infinity();
    if (x < -kMax) return -std::numeric_limits<float>::infinity();
    return static_cast<float>(x);
}

void store(const Vec3& q, size_t v, std::vector<float>& xyz) {
    xyz[3 * v] = to_float(q.x);
    xyz[3 * v + 1] = to_float(q.y);
    xyz[3 * v + 2] = to_float(q.z);
}

void require_finite(const std::vector<double>& values, const std::string& what) {
    for (double v : values) {
        if (!std::isfinite(v)) throw InputError(what + ": non-finite value");
    }
}

}  // namespace

std::vector<int> choose_meshes(const tinygltf::Model& model, const std::vector<std::string>& requests) {
    if (requests.empty()) return {choose_mesh(model, "")};
    std::vector<int> chosen;
    if (requests.size() == 1 && requests[0] == "all") {
        for (size_t i = 0; i < model.meshes.size(); ++i) {
            if (mesh_triangles(model, model.meshes[i]) > 0 && mesh_is_animated(model, static_cast<int>(i))) chosen.push_back(static_cast<int>(i));
        }
        if (chosen.empty()) {
            std::vector<std::string> names;
            for (const tinygltf::Mesh& m : model.meshes) names.push_back(m.name);
            throw UsageError("--mesh all: no skinned or morphed triangle mesh (meshes: " + list_names(names) + ")");
        }
        return chosen;
    }
    for (const std::string& r : requests) {
        if (r == "all") throw UsageError("--mesh all dresses every skinned or morphed mesh: give it alone, not with other --mesh options");
        const int m = choose_mesh(model, r);
        if (std::find(chosen.begin(), chosen.end(), m) != chosen.end()) throw UsageError("--mesh " + r + ": mesh " + std::to_string(m) + " is already chosen");
        chosen.push_back(m);
    }
    return chosen;
}

GltfScene::GltfScene(const tinygltf::Model& model, const std::string& mesh_request, const std::string& clip_request) {
    load_hierarchy(model);
    mesh_index_ = choose_mesh(model, mesh_request);
    init(model, clip_request);
}

GltfScene::GltfScene(const tinygltf::Model& model, int mesh_index, const std::string& clip_request) {
    load_hierarchy(model);
    if (mesh_index < 0 || static_cast<size_t>(mesh_index) >= model.meshes.size()) throw UsageError("mesh " + std::to_string(mesh_index) + " does not exist");
    mesh_index_ = mesh_index;
    init(model, clip_request);
}

void GltfScene::init(const tinygltf::Model& model, const std::string& clip_request) {
    mesh_name_ = model.meshes[static_cast<size_t>(mesh_index_)].name;
    if (mesh_name_.empty()) mesh_name_ = "mesh " + std::to_string(mesh_index_);
    instance_node_ = find_instance_node(model, mesh_index_, node_order_);
    load_mesh(model);
    select_clip(model, clip_request);
    evaluate(nullptr, 0, rest_positions_);
    // Transforms or morph weights so large that the rest pose overflows:
    // nothing can be dressed (poses of the clip may still overflow; the
    // library refuses those frames and keeps the previous one).
    for (size_t i = 0; i < rest_positions_.size(); ++i) {
        if (!std::isfinite(rest_positions_[i])) throw InputError("mesh " + mesh_name_ + ": the rest pose of vertex " + std::to_string(i / 3) + " is not finite (node transforms or morph weights overflow)");
    }
}

void GltfScene::load_hierarchy(const tinygltf::Model& model) {
    const size_t n = model.nodes.size();
    parent_.assign(n, -1);
    nodes_.resize(n);
    for (size_t i = 0; i < n; ++i) {
        const tinygltf::Node& node = model.nodes[i];
        const std::string what = "node " + std::to_string(i);
        for (int c : node.children) {
            if (c < 0 || static_cast<size_t>(c) >= n || static_cast<size_t>(c) == i) throw InputError(what + ": invalid child " + std::to_string(c));
            if (parent_[static_cast<size_t>(c)] >= 0) throw InputError("node " + std::to_string(c) + " has two parents");
            parent_[static_cast<size_t>(c)] = static_cast<int>(i);
        }
        NodeTransform& t = nodes_[i];
        if (!node.matrix.empty()) {
            if (node.matrix.size() != 16) throw InputError(what + ": matrix must have 16 values");
            require_finite(node.matrix, what);
            t.matrix = read_matrix(node.matrix);
        }
        if ((!node.translation.empty() && node.translation.size() != 3) || (!node.rotation.empty() && node.rotation.size() != 4) ||
            (!node.scale.empty() && node.scale.size() != 3)) {
            throw InputError(what + ": malformed translation, rotation or scale");
        }
        require_finite(node.translation, what), require_finite(node.rotation, what), require_finite(node.scale, what);
        if (!node.translation.empty()) t.translation = {node.translation[0], node.translation[1], node.translation[2]};
        if (!node.rotation.empty()) t.rotation = {node.rotation[0], node.rotation[1], node.rotation[2], node.rotation[3]};
        if (!node.scale.empty()) t.scale = {node.scale[0], node.scale[1], node.scale[2]};
    }
    // Parents before children; a node never reached from a root sits on a cycle.
    std::vector<size_t> stack;
    for (size_t i = n; i-- > 0;) {
        if (parent_[i] < 0) stack.push_back(i);
    }
    while (!stack.empty()) {
        const size_t i = stack.back();
        stack.pop_back();
        node_order_.push_back(i);
        const std::vector<int>& children = model.nodes[i].children;
        for (auto c = children.rbegin(); c != children.rend(); ++c) stack.push_back(static_cast<size_t>(*c));
    }
    if (node_order_.size() != n) throw InputError("the node hierarchy has a cycle");
}

void GltfScene::load_mesh(const tinygltf::Model& model) {
    const tinygltf::Mesh& mesh = model.meshes[static_cast<size_t>(mesh_index_)];
    size_t target_count = 0;
    for (const tinygltf::Primitive& p : mesh.primitives) target_count = std::max(target_count, p.targets.size());
    target_deltas_.resize(target_count);

    const int skin = instance_node_ >= 0 ? model.nodes[static_cast<size_t>(instance_node_)].skin : -1;
    if (skin >= 0) load_skin(model, skin);
    for (size_t i = 0; i < mesh.primitives.size(); ++i) {
        if (is_triangle_mode(mesh.primitives[i].mode)) load_primitive(model, i, target_count);
    }
    if (indices_.empty()) throw InputError("mesh " + mesh_name_ + " has no triangles");
    if (skinned()) influence_begin_.push_back(influences_.size());

    // Default weights: the node's, else the mesh's (glTF 2.0, 3.7.2.2).
    base_weights_.assign(target_count, 0.0);
    const std::vector<double>* weights = &mesh.weights;
    if (instance_node_ >= 0 && !model.nodes[static_cast<size_t>(instance_node_)].weights.empty()) {
        weights = &model.nodes[static_cast<size_t>(instance_node_)].weights;
    }
    require_finite(*weights, "morph weights");
    std::copy_n(weights->begin(), std::min(weights->size(), target_count), base_weights_.begin());
}

void GltfScene::load_primitive(const tinygltf::Model& model, size_t index, size_t target_count) {
    const tinygltf::Primitive& p = model.meshes[static_cast<size_t>(mesh_index_)].primitives[index];
    const std::string what = "mesh " + mesh_name_ + " primitive " + std::to_string(index);
    const AccessorData positions = read_accessor(model, attribute(p, "POSITION"), 3, what + " POSITION");
    require_finite(positions.values, what + " POSITION");
    const size_t nv = positions.count;
    const size_t offset = base_positions_.size() / 3;
    // Every morph target keeps a full copy of the positions: bound the total.
    if ((offset + nv) * 3 * std::max<size_t>(target_count, 1) > (size_t{1} << 26)) throw InputError(what + ": too many vertices or morph targets");

    std::vector<uint32_t> local;
    if (p.indices >= 0) {
        local = read_indices(model, p.indices, what + " indices");
    } else {
        local.resize(nv);
        for (size_t i = 0; i < nv; ++i) local[i] = static_cast<uint32_t>(i);
    }
    for (uint32_t i : triangle_list(p.mode, local, what)) {
        if (i >= nv) throw InputError(what + ": index " + std::to_string(i) + " past the vertex count");
        indices_.push_back(static_cast<uint32_t>(offset + i));
    }
    base_positions_.insert(base_positions_.end(), positions.values.begin(), positions.values.end());

    for (size_t t = 0; t < target_count; ++t) {
        std::vector<double>& deltas = target_deltas_[t];
        deltas.resize(offset * 3, 0.0);  // earlier primitives without this target
        const int acc = t < p.targets.size() ? attribute(p.targets[t], "POSITION") : -1;
        if (acc < 0) {
            deltas.resize((offset + nv) * 3, 0.0);
            continue;
        }
        if (accessor_count(model, acc) != nv) throw InputError(what + " target " + std::to_string(t) + ": count differs from POSITION");
        const AccessorData d = read_accessor(model, acc, 3, what + " target " + std::to_string(t));
        require_finite(d.values, what + " target");
        deltas.insert(deltas.end(), d.values.begin(), d.values.end());
    }
    if (skinned()) load_skin_weights(model, index, offset);
}

std::vector<float> GltfScene::vertex_attribute(const tinygltf::Model& model, const std::string& name, int first, int components) const {
    const tinygltf::Mesh& mesh = model.meshes[static_cast<size_t>(mesh_index_)];
    std::vector<float> out;
    out.reserve(vertex_count() * static_cast<size_t>(components));
    for (size_t i = 0; i < mesh.primitives.size(); ++i) {
        const tinygltf::Primitive& p = mesh.primitives[i];
        if (!is_triangle_mode(p.mode)) continue;  // as load_mesh: only triangles are dressed
        const std::string what = "mesh " + mesh_name_ + " primitive " + std::to_string(i);
        const int acc = attribute(p, name);
        if (acc < 0) throw UsageError(what + " has no vertex attribute " + name);
        const AccessorData data = read_accessor(model, acc, what + " " + name);
        if (data.components < first + components) {
            throw UsageError(what + " " + name + " has " + std::to_string(data.components) + " components per vertex, " + std::to_string(first + components) +
                             " needed");
        }
        if (data.count != accessor_count(model, attribute(p, "POSITION"))) throw InputError(what + " " + name + ": count differs from POSITION");
        for (size_t v = 0; v < data.count; ++v) {
            for (int c = 0; c < components; ++c) out.push_back(static_cast<float>(data.at(v, first + c)));
        }
    }
    if (out.size() != vertex_count() * static_cast<size_t>(components)) throw InputError("vertex attribute " + name + ": not one value per vertex");
    for (float x : out) {
        if (!std::isfinite(x)) throw InputError("vertex attribute " + name + " holds a value that is not finite");
    }
    return out;
}

void GltfScene::load_skin(const tinygltf::Model& model, int skin) {
    if (static_cast<size_t>(skin) >= model.skins.size()) throw InputError("node " + std::to_string(instance_node_) + " names a missing skin");
    const tinygltf::Skin& s = model.skins[static_cast<size_t>(skin)];
    const std::string what = "skin " + std::to_string(skin);
    if (s.joints.empty()) throw InputError(what + ": no joints");
    for (int j : s.joints) {
        if (j < 0 || static_cast<size_t>(j) >= model.nodes.size()) throw InputError(what + ": joint " + std::to_string(j) + " is not a node");
    }
    joints_ = s.joints;
    inverse_bind_.assign(joints_.size(), Mat4{});  // absent: identity matrices
    if (s.inverseBindMatrices >= 0) {
        const AccessorData m = read_accessor(model, s.inverseBindMatrices, 16, what + " inverseBindMatrices");
        require_finite(m.values, what);
        if (m.count < joints_.size()) throw InputError(what + ": fewer inverse bind matrices than joints");
        for (size_t j = 0; j < joints_.size(); ++j) std::copy_n(m.values.begin() + static_cast<long>(j * 16), 16, inverse_bind_[j].m.begin());
    }
}

// JOINTS_n / WEIGHTS_n sets; each vertex's influences are renormalized to sum 1.
void GltfScene::load_skin_weights(const tinygltf::Model& model, size_t index, size_t vertex_offset) {
    const tinygltf::Primitive& p = model.meshes[static_cast<size_t>(mesh_index_)].primitives[index];
    const std::string what = "mesh " + mesh_name_ + " primitive " + std::to_string(index);
    const size_t nv = base_positions_.size() / 3 - vertex_offset;
    std::vector<std::vector<Influence>> per_vertex(nv);
    for (int set = 0;; ++set) {
        const std::string n = std::to_string(set);
        const int joints = attribute(p, "JOINTS_" + n), weights = attribute(p, "WEIGHTS_" + n);
        if (joints < 0 || weights < 0) {
            if (set == 0) throw InputError(what + ": skinned but has no JOINTS_0 and WEIGHTS_0");
            break;
        }
        const tinygltf::Accessor& ja = accessor_at(model, joints, what + " JOINTS_" + n);
        const tinygltf::Accessor& wa = accessor_at(model, weights, what + " WEIGHTS_" + n);
        if (ja.normalized || (ja.componentType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE && ja.componentType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT)) {
            throw InputError(what + " JOINTS_" + n + ": must be unsigned bytes or shorts");
        }
        if (wa.componentType != TINYGLTF_COMPONENT_TYPE_FLOAT && !wa.normalized) throw InputError(what + " WEIGHTS_" + n + ": integer weights must be normalized");
        const AccessorData j = read_accessor(model, joints, 4, what + " JOINTS_" + n);
        const AccessorData w = read_accessor(model, weights, 4, what + " WEIGHTS_" + n);
        if (j.count != nv || w.count != nv) throw InputError(what + ": JOINTS_" + n + "/WEIGHTS_" + n + " count differs from POSITION");
        for (size_t v = 0; v < nv; ++v) {
            for (int c = 0; c < 4; ++c) {
                const double weight = w.at(v, c);
                if (!(weight > 0)) continue;  // unused slots may name any joint
                const double joint = j.at(v, c);
                if (joint >= static_cast<double>(joints_.size())) throw InputError(what + ": joint index past the skin's joints");
                per_vertex[v].push_back({static_cast<uint32_t>(joint), weight});
            }
        }
    }
    for (std::vector<Influence>& list : per_vertex) {
        double sum = 0;
        for (const Influence& i : list) sum += i.weight;
        influence_begin_.push_back(influences_.size());
        for (Influence i : list) influences_.push_back({i.joint, i.weight / sum});
    }
}

void GltfScene::select_clip(const tinygltf::Model& model, const std::string& request) {
    std::vector<std::string> names;
    for (const tinygltf::Animation& a : model.animations) names.push_back(a.name);
    if (request.empty()) {
        clip_index_ = names.empty() ? -1 : 0;
    } else {
        clip_index_ = find_by_name_or_index(names, request);
        if (clip_index_ < 0) throw UsageError("--animation " + request + ": no such clip (clips: " + list_names(names) + ")");
    }
    if (clip_index_ < 0) return;
    clip_ = load_clip(model, clip_index_);
    for (const Channel& c : clip_->channels) {
        const size_t node = static_cast<size_t>(c.node);
        if (c.path != TargetPath::Weights && nodes_[node].matrix) {
            throw InputError("animation " + std::to_string(clip_index_) + " animates node " + std::to_string(node) + ", which has a matrix");
        }
        if (c.path == TargetPath::Weights && c.node == instance_node_ &&
            static_cast<size_t>(clip_->samplers[c.sampler].width()) != target_deltas_.size()) {
            throw InputError("animation " + std::to_string(clip_index_) + ": weights channel does not match the morph target count");
        }
    }
}

std::optional<ClipInfo> GltfScene::clip() const {
    if (!clip_) return std::nullopt;
    return ClipInfo{clip_->name, clip_index_, clip_->start, clip_->end - clip_->start};
}

void GltfScene::pose_at(double seconds, std::vector<float>& xyz) const { evaluate(clip_ ? &*clip_ : nullptr, seconds, xyz); }

void GltfScene::apply_clip(const Clip& clip, double seconds, std::vector<NodeTransform>& local, std::vector<double>& weights) const {
    double v[4];
    for (const Channel& c : clip.channels) {
        const Sampler& s = clip.samplers[c.sampler];
        NodeTransform& t = local[static_cast<size_t>(c.node)];
        switch (c.path) {
        case TargetPath::Translation: s.sample(seconds, false, v), t.translation = {v[0], v[1], v[2]}; break;
        case TargetPath::Rotation: s.sample(seconds, true, v), t.rotation = {v[0], v[1], v[2], v[3]}; break;
        case TargetPath::Scale: s.sample(seconds, false, v), t.scale = {v[0], v[1], v[2]}; break;
        case TargetPath::Weights:
            if (c.node == instance_node_) s.sample(seconds, false, weights.data());  // width checked in select_clip
            break;
        }
    }
}

std::vector<Mat4> GltfScene::global_transforms(const std::vector<NodeTransform>& local) const {
    std::vector<Mat4> global(local.size());
    for (size_t i : node_order_) {
        const NodeTransform& t = local[i];
        const Mat4 m = t.matrix ? *t.matrix : compose_trs(t.translation, t.rotation, t.scale);
        global[i] = parent_[i] < 0 ? m : global[static_cast<size_t>(parent_[i])] * m;
    }
    return global;
}

std::vector<double> GltfScene::morphed_positions(const std::vector<double>& weights) const {
    std::vector<double> p = base_positions_;
    for (size_t t = 0; t < target_deltas_.size(); ++t) {
        if (weights[t] == 0) continue;
        for (size_t i = 0; i < p.size(); ++i) p[i] += weights[t] * target_deltas_[t][i];
    }
    return p;
}

// The maps that carry the mesh's own space to the scene: one per joint for
// a skinned mesh (the joint's global transform times its inverse bind
// matrix; the skinned node's own transform is ignored, glTF 2.0, 3.7.3.3),
// else the instancing node's global transform.
std::vector<Mat4> GltfScene::vertex_maps(const std::vector<Mat4>& global) const {
    if (!skinned()) return {instance_node_ >= 0 ? global[static_cast<size_t>(instance_node_)] : Mat4{}};
    std::vector<Mat4> joint(joints_.size());
    for (size_t j = 0; j < joints_.size(); ++j) joint[j] = global[static_cast<size_t>(joints_[j])] * inverse_bind_[j];
    return joint;
}

// Vertex v at mesh-space position p, carried by `maps` (see vertex_maps):
// linear blend skinning by its influences, or placed by the node.
Vec3 GltfScene::posed_vertex(size_t v, const Vec3& p, const std::vector<Mat4>& maps) const {
    if (!skinned()) return transform_point(maps[0], p);
    Vec3 out = influence_begin_[v] == influence_begin_[v + 1] ? p : Vec3{};  // no influence: left in place
    for (size_t k = influence_begin_[v]; k < influence_begin_[v + 1]; ++k) {
        const Vec3 q = transform_point(maps[influences_[k].joint], p);
        const double w = influences_[k].weight;
        out = {out.x + w * q.x, out.y + w * q.y, out.z + w * q.z};
    }
    return out;
}

void GltfScene::evaluate(const Clip* clip, double seconds, std::vector<float>& xyz) const {
    std::vector<NodeTransform> local = nodes_;
    std::vector<double> weights = base_weights_;
    if (clip != nullptr) apply_clip(*clip, seconds, local, weights);
    // Morph first, in the mesh's own space; then skin, or place by the node.
    const std::vector<Mat4> maps = vertex_maps(global_transforms(local));
    const std::vector<double> p = morphed_positions(weights);
    xyz.resize(p.size());
    for (size_t v = 0; v < p.size() / 3; ++v) store(posed_vertex(v, {p[3 * v], p[3 * v + 1], p[3 * v + 2]}, maps), v, xyz);
}

std::optional<SkinSkeleton> GltfScene::skeleton() const {
    if (!skinned()) return std::nullopt;
    SkinSkeleton s;
    const std::vector<Mat4> global = global_transforms(nodes_);
    std::vector<int> joint_of_node(nodes_.size(), -1);
    for (size_t j = 0; j < joints_.size(); ++j) joint_of_node[static_cast<size_t>(joints_[j])] = static_cast<int>(j);
    for (size_t j = 0; j < joints_.size(); ++j) {
        const Mat4& m = global[static_cast<size_t>(joints_[j])];
        for (int r = 0; r < 3; ++r) s.joint_positions.push_back(static_cast<float>(m.at(r, 3)));
        // The parent joint is the nearest ancestor node that is a joint.
        int up = parent_[static_cast<size_t>(joints_[j])];
        while (up >= 0 && joint_of_node[static_cast<size_t>(up)] < 0) up = parent_[static_cast<size_t>(up)];
        s.joint_parents.push_back(up < 0 ? -1 : joint_of_node[static_cast<size_t>(up)]);
    }
    const size_t n = influence_begin_.size() - 1;
    size_t width = 1;
    for (size_t v = 0; v < n; ++v) width = std::max(width, influence_begin_[v + 1] - influence_begin_[v]);
    s.influences = static_cast<uint32_t>(std::min<size_t>(width, 16));
    for (size_t v = 0; v < n; ++v) {
        for (size_t k = 0; k < s.influences; ++k) {
            const size_t at = influence_begin_[v] + k;
            const bool used = at < influence_begin_[v + 1];
            s.vertex_joints.push_back(used ? influences_[at].joint : 0);
            s.vertex_weights.push_back(used ? static_cast<float>(influences_[at].weight) : 0.0f);
        }
    }
    return s;
}

std::vector<float> GltfScene::rest_directions(const tinygltf::Model& model, const std::string& name, int first) const {
    const std::vector<float> mesh_space = vertex_attribute(model, name, first, 3);
    const std::vector<Mat4> maps = vertex_maps(global_transforms(nodes_));
    const std::vector<double> p = morphed_positions(base_weights_);
    std::vector<float> out(mesh_space.size());
    for (size_t v = 0; v < p.size() / 3; ++v) {
        // Each vertex's map is affine, so T(p + d) - T(p) is its linear part applied to d.
        const Vec3 at{p[3 * v], p[3 * v + 1], p[3 * v + 2]};
        const Vec3 d{mesh_space[3 * v], mesh_space[3 * v + 1], mesh_space[3 * v + 2]};
        const Vec3 a = posed_vertex(v, at, maps), b = posed_vertex(v, {at.x + d.x, at.y + d.y, at.z + d.z}, maps);
        store({b.x - a.x, b.y - a.y, b.z - a.z}, v, out);
    }
    return out;
}

}  // namespace plumage_host
