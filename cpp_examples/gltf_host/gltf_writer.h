// Records the run (body and feathers per frame) and writes it as a .glb:
// two meshes whose per-frame positions are morph targets, and one
// animation whose STEP weights switch on one target per frame.
#pragma once

#include "plumage.h"

#include <cstdint>
#include <string>
#include <unordered_map>
#include <vector>

namespace plumage_host {

class AnimationRecorder {
public:
    // The rest pose: the body soup and the feathers as the library made them.
    AnimationRecorder(std::vector<float> body_rest, std::vector<uint32_t> body_indices, const std::vector<PlumageFeather>& feathers,
                      std::vector<float> feather_triangles);

    // One stepped frame at `seconds` (clip time).
    void add_frame(double seconds, const std::vector<float>& body, const std::vector<PlumageFeather>& feathers,
                   const std::vector<float>& feather_triangles);

    // Feathers of a frame that were not at rest (by id); they are left out.
    size_t untracked_feathers() const { return untracked_; }

    // Writes the .glb (throws OutputError).
    void write_glb(const std::string& path) const;

private:
    std::vector<float> arrange_feathers(const std::vector<PlumageFeather>& feathers, const std::vector<float>& triangles,
                                        const std::vector<float>& previous);

    std::vector<float> body_rest_;
    std::vector<uint32_t> body_indices_;
    std::vector<float> feather_rest_;  // 18 floats per feather, rest order
    std::unordered_map<uint64_t, size_t> slot_of_id_;
    std::vector<double> times_;
    std::vector<std::vector<float>> body_frames_;
    std::vector<std::vector<float>> feather_frames_;
    size_t untracked_ = 0;
};

}  // namespace plumage_host
