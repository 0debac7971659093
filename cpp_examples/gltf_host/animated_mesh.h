// What the host drives the library with: a triangle soup at rest and its
// pose at any clip time, in the same vertex numbering.
#pragma once

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
    // The direction the model faces at rest: +Z by glTF's convention.
    virtual std::array<float, 3> facing() const { return {0.0f, 0.0f, 1.0f}; }

    size_t vertex_count() const { return rest_positions().size() / 3; }
    size_t triangle_count() const { return triangles().size() / 3; }
};

}  // namespace plumage_host
