// Fuzz target for the host's glTF reader: bytes (a .glb container or a
// .gltf JSON document) -> tinygltf model -> the animated mesh the host
// dresses (GltfScene: hierarchy, morph targets, skin, clip) -> its rest
// pose, poses across the clip and the vertex attributes the host reads.
//
// A refusal (InputError, UsageError) is a correct answer. Anything else
// is a bug: a sanitizer report, a crash, another exception escaping (the
// host would report it as an internal error), a hang or an allocation past
// libFuzzer's limits.
//
// Built two ways: with clang's libFuzzer (scripts/fuzz_gltf.sh) and as a
// plain program (gltf_fuzz_replay.cpp) that ctest runs over the seed corpus
// and every crash input kept in cpp_examples/fuzz/regressions.
#include "errors.h"
#include "gltf_loader.h"
#include "gltf_scene.h"

#include <tiny_gltf.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <new>
#include <string>
#include <vector>

namespace {

using namespace plumage_host;

[[noreturn]] void found(const char* what, const char* detail) {
    std::fprintf(stderr, "gltf_fuzz: %s: %s\n", what, detail);
    std::abort();
}

void exercise(const std::vector<unsigned char>& bytes) {
    // External buffers resolve against a directory that does not exist, so
    // an input never reads files of the machine it runs on.
    const tinygltf::Model model = load_gltf_memory(bytes, "input", "/nonexistent-plumage-fuzz");
    GltfScene scene(model, "", "");
    const std::vector<float>& rest = scene.rest_positions();
    const std::vector<uint32_t>& tris = scene.triangles();
    if (rest.size() % 3 != 0 || tris.size() % 3 != 0) found("bad mesh shape", "positions or indices not in threes");
    const size_t vertices = rest.size() / 3;
    for (uint32_t v : tris) {
        if (v >= vertices) found("index out of range", std::to_string(v).c_str());
    }
    for (float x : rest) {
        if (!std::isfinite(x)) found("non-finite rest position", "a rest coordinate is not finite");
    }
    // Poses across the clip (or the rest pose without one), and outside it.
    std::vector<float> xyz;
    const auto clip = scene.clip();
    const double start = clip ? clip->start : 0.0, duration = clip ? clip->duration : 0.0;
    for (double f : {0.0, 0.37, 1.0, -1.0, 2.5}) {
        scene.pose_at(start + f * duration, xyz);
        if (xyz.size() != rest.size()) found("pose size", "a pose has another vertex count than the rest pose");
    }
    // The attributes the host may read for maps, flow and texture.
    for (const char* name : {"NORMAL", "TEXCOORD_0", "COLOR_0", "_SPACING"}) {
        try {
            (void)scene.vertex_attribute(model, name, 0, 1);
            (void)scene.vertex_attribute(model, name, 1, 2);
            (void)scene.rest_directions(model, name, 0);
        } catch (const UsageError&) {
        } catch (const InputError&) {
        }
    }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    try {
        exercise(std::vector<unsigned char>(data, data + size));
    } catch (const InputError&) {
    } catch (const UsageError&) {
    } catch (const std::bad_alloc&) {
        found("std::bad_alloc", "an allocation the input asked for failed (bound it and refuse)");
    } catch (const std::exception& e) {
        found("unexpected exception", e.what());
    }
    return 0;
}
