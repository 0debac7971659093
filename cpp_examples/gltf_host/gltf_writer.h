// Records the run (body and feathers per frame) and writes it as a .glb:
// two meshes whose per-frame positions are morph targets, and one
// animation whose STEP weights switch on one target per frame.
#pragma once

#include "plumage.h"
#include "plumage_system.h"

#include <cstdint>
#include <string>
#include <unordered_map>
#include <vector>

namespace plumage_host {

class AnimationRecorder {
public:
    // The rest pose: the body soup and the feathers as the library made them.
    AnimationRecorder(std::vector<float> body_rest, std::vector<uint32_t> body_indices, const std::vector<PlumageFeather>& feathers,
                      FeatherMeshData feather_mesh);

    // One stepped frame at `seconds` (clip time).
    void add_frame(double seconds, const std::vector<float>& body, const std::vector<PlumageFeather>& feathers, const FeatherMeshData& feather_mesh);

    // Feathers of a frame that were not at rest (by id); they are left out.
    size_t untracked_feathers() const { return untracked_; }

    // Writes the .glb (throws OutputError): the feathers' mesh carries
    // NORMAL, TEXCOORD_0 (u along the shaft, v across the vanes) and
    // _FEATHER_ID (the feather's index at rest, a float), and every frame's
    // morph target moves positions and normals.
    void write_glb(const std::string& path) const;

private:
    // Positions and normals of a frame in the rest pose's feather order.
    std::pair<std::vector<float>, std::vector<float>> arrange_feathers(const std::vector<PlumageFeather>& feathers, const FeatherMeshData& mesh);

    std::vector<float> body_rest_;
    std::vector<uint32_t> body_indices_;
    FeatherMeshData feather_rest_;
    std::vector<size_t> first_vertex_;  // per rest feather
    std::unordered_map<uint64_t, size_t> slot_of_id_;
    std::vector<double> times_;
    std::vector<std::vector<float>> body_frames_;
    std::vector<std::vector<float>> feather_frames_;
    std::vector<std::vector<float>> normal_frames_;
    size_t untracked_ = 0;
};

}  // namespace plumage_host
