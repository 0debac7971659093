// The built-in model: an elongated body (head at x = 0, tail at x = 4,
// y up) that bends sideways with a travelling wave, growing toward the
// tail. It starts straight and the wave fades in over the first half
// second, so the rest pose is the pose at t = 0. Like a UV-mapped glTF
// mesh, it is a soup with a duplicated seam for the library to weld.
#pragma once

#include "animated_mesh.h"

namespace plumage_host {

class ProceduralBody final : public AnimatedMesh {
public:
    // `rings` cross-sections of `segments` vertices each: 2 * segments * (rings - 2)
    // triangles (defaults: 6016; plumage_gltf --model-resolution RINGS,SEGMENTS).
    explicit ProceduralBody(int rings = kRings, int segments = kSegments);

    std::string mesh_name() const override { return "procedural_body"; }
    const std::vector<float>& rest_positions() const override { return rest_; }
    const std::vector<uint32_t>& triangles() const override { return indices_; }
    std::optional<ClipInfo> clip() const override { return ClipInfo{"swim", 0, 0.0, kDuration}; }
    void pose_at(double seconds, std::vector<float>& xyz) const override;
    // The head is at x = 0 and the body runs along +x to the tail.
    std::array<float, 3> facing() const override { return {-1.0f, 0.0f, 0.0f}; }

    static constexpr double kDuration = 2.0;
    static constexpr int kRings = 96, kSegments = 32;  // the default resolution

private:
    int rings_;
    int segments_;
    std::vector<uint32_t> indices_;
    std::vector<float> rest_;
};

}  // namespace plumage_host
