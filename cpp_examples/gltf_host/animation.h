// glTF animation clips: samplers (STEP, LINEAR, CUBICSPLINE) and the
// channels that drive node translation, rotation, scale and morph weights.
#pragma once

#include <string>
#include <vector>

namespace tinygltf {
class Model;
}

namespace plumage_host {

enum class Interpolation { Step, Linear, CubicSpline };
enum class TargetPath { Translation, Rotation, Scale, Weights };

// One sampler: key times and `width` values per key (three groups of
// `width` per key for CUBICSPLINE: in-tangent, value, out-tangent).
class Sampler {
public:
    Sampler(std::vector<double> times, std::vector<double> values, int width, Interpolation interpolation);

    // Writes `width` values at time t into out (clamped outside the keys).
    // Rotations are interpolated on the shorter arc and normalized.
    void sample(double t, bool rotation, double* out) const;

    int width() const { return width_; }
    double first_time() const { return times_.front(); }
    double last_time() const { return times_.back(); }

private:
    const double* value(size_t key) const;
    const double* in_tangent(size_t key) const;
    const double* out_tangent(size_t key) const;

    std::vector<double> times_;
    std::vector<double> values_;
    int width_;
    Interpolation interpolation_;
};

struct Channel {
    int node = -1;
    TargetPath path = TargetPath::Translation;
    size_t sampler = 0;
};

struct Clip {
    std::string name;
    std::vector<Sampler> samplers;
    std::vector<Channel> channels;
    double start = 0;
    double end = 0;
};

// Reads and checks animation `index` (throws InputError).
Clip load_clip(const tinygltf::Model& model, int index);

}  // namespace plumage_host
