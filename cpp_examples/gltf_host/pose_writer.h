// Writes what the host hands the library (--poses FILE): the rest mesh, the
// configuration, the per-vertex maps and every stepped frame's positions,
// so that another program (the Python package's `dress` command) can drive
// the library with exactly the same input. Little-endian, native layout:
//
//   char     magic[8]        "PLMPOSE\0"
//   uint32_t version         1; 2 when a layer map or a skeleton is present; 3 when
//                            feather types are (the lowest that holds what is written)
//   uint32_t config_size     sizeof(PlumageConfig)
//   uint64_t vertex_count, triangle_count, frame_count
//   double   fps
//   uint32_t maps            bit 0 spacing, 1 length, 2 width, 3 flow; version 2 also
//                            bit 4 layer, 5 skeleton; version 3 also bit 6 feather types
//   uint32_t reserved        0
//   PlumageConfig config     as created with (progress pointers zeroed)
//   float    rest[3 * vertex_count]
//   uint32_t indices[3 * triangle_count]
//   double   times[frame_count]           clip seconds of each frame
//   float    spacing[vertex_count], length[...], width[...], flow[3 * vertex_count]   (those present)
//   float    layer[vertex_count]                                                       (if present)
//   skeleton (if present): uint32_t joint_count, influences; int32_t head_joint;
//            uint32_t reserved 0; float joint_positions[3 * joint_count];
//            int32_t joint_parents[joint_count]; uint32_t vertex_joints[influences * vertex_count];
//            float vertex_weights[influences * vertex_count]   (as PlumageSkeleton gets them)
//   feather types (if present): uint32_t type_count, reserved 0; uint32_t types[type_count]
//            (PLUMAGE_PRESET_* each type is initialised from); uint32_t feather_type[vertex_count]
//   float    frames[frame_count][3 * vertex_count]
#pragma once

#include "plumage.h"
#include "plumage_system.h"

#include <cstdio>
#include <string>
#include <vector>

namespace plumage_host {

class PoseWriter {
public:
    // Writes everything up to the frames (throws OutputError).
    PoseWriter(const std::string& path, PlumageConfig cfg, double fps, const std::vector<float>& rest, const std::vector<uint32_t>& indices,
               const std::vector<double>& times, const VertexMaps& maps);
    ~PoseWriter();
    PoseWriter(const PoseWriter&) = delete;
    PoseWriter& operator=(const PoseWriter&) = delete;

    void add_frame(const std::vector<float>& positions);
    // Flushes and closes; throws OutputError unless every announced frame was written.
    void finish();

private:
    void write(const void* data, size_t bytes);

    std::string path_;
    std::FILE* file_ = nullptr;
    size_t frames_expected_ = 0;
    size_t frames_written_ = 0;
};

}  // namespace plumage_host
