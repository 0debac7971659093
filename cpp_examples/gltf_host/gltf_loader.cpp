#include "gltf_loader.h"

#include "errors.h"

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <vector>

namespace plumage_host {
namespace {

// tinygltf's messages may span lines; the host reports one line.
std::string one_line(std::string text) {
    for (char& c : text) {
        if (c == '\n' || c == '\r') c = ' ';
    }
    while (!text.empty() && text.back() == ' ') text.pop_back();
    return text.empty() ? "unknown error" : text;
}

std::vector<unsigned char> read_file(const std::string& path) {
    std::error_code ec;
    if (std::filesystem::is_directory(path, ec)) throw InputError(path + ": is a directory");
    std::ifstream in(path, std::ios::binary);
    if (!in) throw InputError(path + ": cannot open: " + std::strerror(errno));
    std::vector<unsigned char> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    if (in.bad()) throw InputError(path + ": read error");
    return bytes;
}

// The image callback: keep the encoded bytes, decode nothing.
bool skip_image(tinygltf::Image*, const int, std::string*, std::string*, int, int, const unsigned char*, int, void*) {
    return true;
}

bool looks_like_json(const std::vector<unsigned char>& bytes) {
    for (unsigned char c : bytes) {
        if (c == ' ' || c == '\t' || c == '\n' || c == '\r') continue;
        return c == '{';
    }
    return false;
}

}  // namespace

bool is_supported_required_extension(const std::string& name) {
    // KHR_mesh_quantization only widens accessor types, which the accessor
    // reader handles. Material, texture and light extensions change nothing
    // the host reads (it never reads materials or pixels). Anything else may
    // change geometry or animation (Draco, meshopt, animation pointers,
    // instancing): refused rather than misread.
    if (name == "KHR_mesh_quantization" || name == "KHR_lights_punctual") return true;
    for (const char* prefix : {"KHR_materials_", "KHR_texture_", "EXT_texture_"}) {
        if (name.rfind(prefix, 0) == 0) return true;
    }
    return false;
}

tinygltf::Model load_gltf_file(const std::string& path) {
    const std::vector<unsigned char> bytes = read_file(path);
    return load_gltf_memory(bytes, path, std::filesystem::path(path).parent_path().string());
}

tinygltf::Model load_gltf_memory(const std::vector<unsigned char>& bytes, const std::string& path, const std::string& base_dir) {
    if (bytes.empty()) throw InputError(path + ": empty file");
    if (bytes.size() > std::numeric_limits<unsigned int>::max()) throw InputError(path + ": larger than 4 GiB");
    const bool binary = bytes.size() >= 4 && std::memcmp(bytes.data(), "glTF", 4) == 0;
    if (!binary && !looks_like_json(bytes)) throw InputError(path + ": not a glTF file (neither a GLB container nor JSON)");

    tinygltf::TinyGLTF loader;
    loader.SetImageLoader(&skip_image, nullptr);
    tinygltf::Model model;
    std::string err, warn;
    bool ok = false;
    try {
        const auto size = static_cast<unsigned int>(bytes.size());
        ok = binary ? loader.LoadBinaryFromMemory(&model, &err, &warn, bytes.data(), size, base_dir)
                    : loader.LoadASCIIFromString(&model, &err, &warn, reinterpret_cast<const char*>(bytes.data()), size, base_dir);
    } catch (const std::exception& e) {
        ok = false;
        err = e.what();
    }
    if (!ok) throw InputError(path + ": invalid glTF: " + one_line(err));

    for (const std::string& ext : model.extensionsRequired) {
        if (!is_supported_required_extension(ext)) throw InputError(path + ": requires the unsupported extension " + ext);
    }
    return model;
}

}  // namespace plumage_host
