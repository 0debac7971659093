// Bounds-checked reading of glTF accessors: every component type, the
// `normalized` flag, byte strides, accessors without a buffer view (all
// zeros) and sparse substitution. Malformed data throws InputError.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace tinygltf {
class Model;
}

namespace plumage_host {

// An accessor's elements as doubles, `components` per element.
struct AccessorData {
    size_t count = 0;
    int components = 0;
    std::vector<double> values;

    double at(size_t element, int component) const {
        return values[element * static_cast<size_t>(components) + static_cast<size_t>(component)];
    }
};

// Reads accessor `index`; `what` names it in error messages. Normalized
// integers become floats as the glTF spec says; other integers keep their value.
AccessorData read_accessor(const tinygltf::Model& model, int index, const std::string& what);

// As read_accessor, but insists on `components` per element.
AccessorData read_accessor(const tinygltf::Model& model, int index, int components, const std::string& what);

// Reads an index-like accessor (unsigned integer scalars), e.g. triangle indices.
std::vector<uint32_t> read_indices(const tinygltf::Model& model, int index, const std::string& what);

}  // namespace plumage_host
