// One mesh of a glTF model, evaluated at any time of one animation clip:
// node hierarchy (TRS or matrix), morph targets and skins.
#pragma once

#include "animated_mesh.h"
#include "animation.h"
#include "math3d.h"

#include <optional>
#include <string>
#include <vector>

namespace tinygltf {
class Model;
}

namespace plumage_host {

// The meshes the --mesh options name, in their order: none = the default
// mesh (the largest skinned or morphed one, else the largest); "all" alone =
// every skinned or morphed mesh with triangles, by index; else each by name
// or index. Throws UsageError for a mesh that does not exist, one named
// twice, "all" with others or without any deforming mesh.
std::vector<int> choose_meshes(const tinygltf::Model& model, const std::vector<std::string>& requests);

class GltfScene final : public AnimatedMesh {
public:
    // Picks the mesh named (or numbered) `mesh_request`, else the largest
    // skinned or morphed mesh, else the largest mesh; and the clip named or
    // numbered `clip_request`, else clip 0 when there is one. Throws
    // UsageError for a mesh or clip that does not exist, InputError for
    // content the host cannot read.
    GltfScene(const tinygltf::Model& model, const std::string& mesh_request, const std::string& clip_request);
    // Mesh `mesh_index` (one of choose_meshes' answers).
    GltfScene(const tinygltf::Model& model, int mesh_index, const std::string& clip_request);

    std::string mesh_name() const override { return mesh_name_; }
    const std::vector<float>& rest_positions() const override { return rest_positions_; }
    const std::vector<uint32_t>& triangles() const override { return indices_; }
    std::optional<ClipInfo> clip() const override;
    void pose_at(double seconds, std::vector<float>& xyz) const override;

    // Vertex attribute `name` of the dressed mesh (the `model` it was read
    // from), in the order of rest_positions(): `components` values per
    // vertex from component `first`. Throws UsageError when a triangle
    // primitive lacks the attribute or has too few components, InputError
    // for unreadable or non-finite data.
    std::vector<float> vertex_attribute(const tinygltf::Model& model, const std::string& name, int first, int components) const;

    // Directions given by vertex attribute `name` (components first to
    // first + 2, in the mesh's own space) carried to the rest pose the way
    // rest_positions() are: by the node transforms and the skin.
    std::vector<float> rest_directions(const tinygltf::Model& model, const std::string& name, int first) const;

    // The skin's joints at the rest pose and every vertex's influences.
    std::optional<SkinSkeleton> skeleton() const override;

    int mesh_index() const { return mesh_index_; }
    bool skinned() const { return !joints_.empty(); }
    size_t morph_target_count() const { return target_deltas_.size(); }

private:
    struct NodeTransform {
        Vec3 translation;
        Quat rotation;
        Vec3 scale{1, 1, 1};
        std::optional<Mat4> matrix;  // a node with a matrix is never animated
    };
    struct Influence {
        uint32_t joint = 0;  // index into joints_
        double weight = 0;
    };

    void init(const tinygltf::Model& model, const std::string& clip_request);
    void load_hierarchy(const tinygltf::Model& model);
    void load_mesh(const tinygltf::Model& model);
    void load_primitive(const tinygltf::Model& model, size_t primitive, size_t target_count);
    void load_skin(const tinygltf::Model& model, int skin);
    void load_skin_weights(const tinygltf::Model& model, size_t primitive, size_t vertex_offset);
    void select_clip(const tinygltf::Model& model, const std::string& request);
    void evaluate(const Clip* clip, double seconds, std::vector<float>& xyz) const;
    void apply_clip(const Clip& clip, double seconds, std::vector<NodeTransform>& local, std::vector<double>& weights) const;
    std::vector<Mat4> global_transforms(const std::vector<NodeTransform>& local) const;
    std::vector<double> morphed_positions(const std::vector<double>& weights) const;
    std::vector<Mat4> vertex_maps(const std::vector<Mat4>& global) const;
    Vec3 posed_vertex(size_t v, const Vec3& p, const std::vector<Mat4>& maps) const;

    int mesh_index_ = -1;
    std::string mesh_name_;
    int instance_node_ = -1;  // the node that instantiates the mesh (-1: none)

    std::vector<NodeTransform> nodes_;
    std::vector<int> parent_;
    std::vector<size_t> node_order_;  // parents before children

    std::vector<double> base_positions_;
    std::vector<uint32_t> indices_;
    std::vector<std::vector<double>> target_deltas_;
    std::vector<double> base_weights_;

    std::vector<int> joints_;
    std::vector<Mat4> inverse_bind_;
    std::vector<size_t> influence_begin_;  // per vertex, into influences_ (CSR)
    std::vector<Influence> influences_;

    std::optional<Clip> clip_;
    int clip_index_ = -1;
    std::vector<float> rest_positions_;
};

}  // namespace plumage_host
