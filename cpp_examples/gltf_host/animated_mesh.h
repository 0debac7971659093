// What the host drives the library with: a triangle soup at rest and its
// pose at any clip time, in the same vertex numbering.
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace plumage_host {

struct ClipInfo {
    std::string name;
    int index = 0;
    double start = 0;     // seconds
    double duration = 0;  // seconds
};

// The skeleton a mesh is skinned to, as PlumageSkeleton takes it: joint
// positions at the rest pose (the space of rest_positions()), each joint's
// parent (-1: a root), and `influences` (joint, weight) slots per vertex,
// unused ones with weight 0.
struct SkinSkeleton {
    std::vector<float> joint_positions;
    std::vector<int32_t> joint_parents;
    uint32_t influences = 0;
    std::vector<uint32_t> vertex_joints;
    std::vector<float> vertex_weights;

    size_t joint_count() const { return joint_parents.size(); }
    // `other`'s joints after these and its vertices after these vertices:
    // the skeleton of two meshes dressed as one (both skinned).
    void append(const SkinSkeleton& other) {
        const uint32_t width = std::max(influences, other.influences);
        const auto widen = [width](const SkinSkeleton& s, uint32_t offset, std::vector<uint32_t>& joints, std::vector<float>& weights) {
            for (size_t v = 0; s.influences > 0 && v < s.vertex_joints.size() / s.influences; ++v) {
                for (uint32_t k = 0; k < width; ++k) {
                    const bool used = k < s.influences;
                    joints.push_back(used ? s.vertex_joints[v * s.influences + k] + offset : 0);
                    weights.push_back(used ? s.vertex_weights[v * s.influences + k] : 0.0f);
                }
            }
        };
        const auto offset = static_cast<uint32_t>(joint_count());
        std::vector<uint32_t> joints;
        std::vector<float> weights;
        widen(*this, 0, joints, weights);
        widen(other, offset, joints, weights);
        for (int32_t p : other.joint_parents) joint_parents.push_back(p < 0 ? -1 : p + static_cast<int32_t>(offset));
        joint_positions.insert(joint_positions.end(), other.joint_positions.begin(), other.joint_positions.end());
        vertex_joints = std::move(joints), vertex_weights = std::move(weights), influences = width;
    }
};

class AnimatedMesh {
public:
    virtual ~AnimatedMesh() = default;

    virtual std::string mesh_name() const = 0;
    // xyz per vertex at the rest pose (no animation applied).
    virtual const std::vector<float>& rest_positions() const = 0;
    // Three vertex indices per triangle.
    virtual const std::vector<uint32_t>& triangles() const = 0;
    // The selected clip, if the input has one.
    virtual std::optional<ClipInfo> clip() const = 0;
    // xyz per vertex at clip time `seconds`.
    virtual void pose_at(double seconds, std::vector<float>& xyz) const = 0;
    // The skeleton the mesh is skinned to, if it is.
    virtual std::optional<SkinSkeleton> skeleton() const { return std::nullopt; }
    // The direction the model faces at rest: +Z by glTF's convention.
    virtual std::array<float, 3> facing() const { return {0.0f, 0.0f, 1.0f}; }

    size_t vertex_count() const { return rest_positions().size() / 3; }
    size_t triangle_count() const { return triangles().size() / 3; }
};

}  // namespace plumage_host
