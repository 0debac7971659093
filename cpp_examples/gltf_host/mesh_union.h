// Several animated meshes handed to the library as one triangle soup: their
// vertices and triangles one after the other, in the order given. One
// library system over the union keeps the feathers of every mesh clear of
// each other's; each mesh's own figures come from the library's per-part
// calls over its range of triangles.
#pragma once

#include "animated_mesh.h"

#include <memory>
#include <string>
#include <vector>

namespace plumage_host {

// Where one mesh sits in the union.
struct MeshPart {
    std::string name;
    int index = 0;  // the mesh's index in the input (0 for the built-in model)
    size_t first_vertex = 0, vertex_count = 0;
    size_t first_triangle = 0, triangle_count = 0;
};

class MeshUnion final : public AnimatedMesh {
public:
    // `meshes` and `indices` (the input's mesh index of each) are in the
    // same order; the clip is the first mesh's (every one was asked for the
    // same clip).
    MeshUnion(std::vector<std::unique_ptr<AnimatedMesh>> meshes, const std::vector<int>& indices) : meshes_(std::move(meshes)) {
        for (size_t m = 0; m < meshes_.size(); ++m) {
            const AnimatedMesh& mesh = *meshes_[m];
            MeshPart part{mesh.mesh_name(), indices[m], rest_.size() / 3, mesh.vertex_count(), triangles_.size() / 3, mesh.triangle_count()};
            for (uint32_t v : mesh.triangles()) triangles_.push_back(static_cast<uint32_t>(part.first_vertex + v));
            rest_.insert(rest_.end(), mesh.rest_positions().begin(), mesh.rest_positions().end());
            name_ += (m ? ", " : "") + part.name;
            parts_.push_back(std::move(part));
        }
    }

    std::string mesh_name() const override { return name_; }
    const std::vector<float>& rest_positions() const override { return rest_; }
    const std::vector<uint32_t>& triangles() const override { return triangles_; }
    std::optional<ClipInfo> clip() const override { return meshes_.front()->clip(); }
    void pose_at(double seconds, std::vector<float>& xyz) const override {
        xyz.clear();
        for (const auto& mesh : meshes_) {
            mesh->pose_at(seconds, scratch_);
            xyz.insert(xyz.end(), scratch_.begin(), scratch_.end());
        }
    }
    std::array<float, 3> facing() const override { return meshes_.front()->facing(); }
    // Every mesh's skeleton, one after the other (each its own trees of
    // joints); none unless every mesh is skinned.
    std::optional<SkinSkeleton> skeleton() const override {
        std::optional<SkinSkeleton> all;
        for (const auto& mesh : meshes_) {
            std::optional<SkinSkeleton> s = mesh->skeleton();
            if (!s) return std::nullopt;
            if (all) all->append(*s);
            else all = std::move(s);
        }
        return all;
    }

    const std::vector<MeshPart>& parts() const { return parts_; }
    const AnimatedMesh& mesh(size_t m) const { return *meshes_[m]; }

private:
    std::vector<std::unique_ptr<AnimatedMesh>> meshes_;
    std::vector<MeshPart> parts_;
    std::string name_;
    std::vector<float> rest_;
    std::vector<uint32_t> triangles_;
    mutable std::vector<float> scratch_;
};

}  // namespace plumage_host
