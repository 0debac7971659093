#include "animation.h"

#include "accessor.h"
#include "errors.h"
#include "math3d.h"

#include <tiny_gltf.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace plumage_host {
namespace {

Interpolation parse_interpolation(const std::string& name, const std::string& what) {
    if (name == "LINEAR") return Interpolation::Linear;
    if (name == "STEP") return Interpolation::Step;
    if (name == "CUBICSPLINE") return Interpolation::CubicSpline;
    throw InputError(what + ": unsupported interpolation \"" + name + "\"");
}

Sampler load_sampler(const tinygltf::Model& model, const tinygltf::AnimationSampler& s, const std::string& what) {
    const AccessorData input = read_accessor(model, s.input, 1, what + " input");
    if (input.count == 0) throw InputError(what + ": no keys");
    for (size_t i = 0; i < input.count; ++i) {
        if (!std::isfinite(input.values[i])) throw InputError(what + ": non-finite key time");
        if (i > 0 && input.values[i] < input.values[i - 1]) throw InputError(what + ": key times decrease");
    }
    const Interpolation interpolation = parse_interpolation(s.interpolation, what);
    AccessorData output = read_accessor(model, s.output, what + " output");
    const size_t groups = input.count * (interpolation == Interpolation::CubicSpline ? 3 : 1);
    const size_t total = output.values.size();
    if (total == 0 || total % groups != 0) throw InputError(what + ": output count does not match the key count");
    for (double v : output.values) {
        if (!std::isfinite(v)) throw InputError(what + ": non-finite output value");
    }
    return Sampler(input.values, std::move(output.values), static_cast<int>(total / groups), interpolation);
}

// Returns false for channels this host leaves alone (no target node: e.g. KHR_animation_pointer).
bool parse_target(const std::string& path, TargetPath& out) {
    if (path == "translation") out = TargetPath::Translation;
    else if (path == "rotation") out = TargetPath::Rotation;
    else if (path == "scale") out = TargetPath::Scale;
    else if (path == "weights") out = TargetPath::Weights;
    else return false;
    return true;
}

int expected_width(TargetPath path) {
    switch (path) {
    case TargetPath::Rotation: return 4;
    case TargetPath::Weights: return 0;  // one per morph target: checked by the scene
    default: return 3;
    }
}

}  // namespace

Sampler::Sampler(std::vector<double> times, std::vector<double> values, int width, Interpolation interpolation)
    : times_(std::move(times)), values_(std::move(values)), width_(width), interpolation_(interpolation) {}

const double* Sampler::value(size_t key) const {
    const size_t w = static_cast<size_t>(width_);
    return interpolation_ == Interpolation::CubicSpline ? &values_[(3 * key + 1) * w] : &values_[key * w];
}
const double* Sampler::in_tangent(size_t key) const { return &values_[3 * key * static_cast<size_t>(width_)]; }
const double* Sampler::out_tangent(size_t key) const { return &values_[(3 * key + 2) * static_cast<size_t>(width_)]; }

void Sampler::sample(double t, bool rotation, double* out) const {
    const size_t n = times_.size();
    const size_t w = static_cast<size_t>(width_);
    if (n == 1 || t <= times_.front() || t >= times_.back()) {
        const double* v = value(n == 1 || t <= times_.front() ? 0 : n - 1);
        std::copy(v, v + w, out);
        return;
    }
    // times_[k] <= t < times_[k + 1], so td > 0.
    const size_t k = static_cast<size_t>(std::upper_bound(times_.begin(), times_.end(), t) - times_.begin()) - 1;
    const double td = times_[k + 1] - times_[k];
    const double s = (t - times_[k]) / td;
    const double* a = value(k);
    const double* b = value(k + 1);
    switch (interpolation_) {
    case Interpolation::Step: std::copy(a, a + w, out); return;
    case Interpolation::Linear:
        if (rotation && w == 4) {
            const Quat q = slerp({a[0], a[1], a[2], a[3]}, {b[0], b[1], b[2], b[3]}, s);
            out[0] = q.x, out[1] = q.y, out[2] = q.z, out[3] = q.w;
        } else {
            for (size_t i = 0; i < w; ++i) out[i] = a[i] + s * (b[i] - a[i]);
        }
        return;
    case Interpolation::CubicSpline: {
        // Hermite spline; the stored tangents are per second, hence the td factor.
        const double s2 = s * s, s3 = s2 * s;
        const double h00 = 2 * s3 - 3 * s2 + 1, h10 = s3 - 2 * s2 + s, h01 = -2 * s3 + 3 * s2, h11 = s3 - s2;
        const double* out_a = out_tangent(k);
        const double* in_b = in_tangent(k + 1);
        for (size_t i = 0; i < w; ++i) out[i] = h00 * a[i] + h10 * td * out_a[i] + h01 * b[i] + h11 * td * in_b[i];
        if (rotation && w == 4) {
            const Quat q = normalized({out[0], out[1], out[2], out[3]});
            out[0] = q.x, out[1] = q.y, out[2] = q.z, out[3] = q.w;
        }
        return;
    }
    }
}

Clip load_clip(const tinygltf::Model& model, int index) {
    const tinygltf::Animation& anim = model.animations.at(static_cast<size_t>(index));
    const std::string what = "animation " + std::to_string(index);
    Clip clip;
    clip.name = anim.name;
    for (size_t i = 0; i < anim.samplers.size(); ++i) {
        clip.samplers.push_back(load_sampler(model, anim.samplers[i], what + " sampler " + std::to_string(i)));
    }
    double start = std::numeric_limits<double>::infinity(), end = -start;
    for (const tinygltf::AnimationChannel& c : anim.channels) {
        Channel channel;
        if (c.target_node < 0 || !parse_target(c.target_path, channel.path)) continue;
        if (static_cast<size_t>(c.target_node) >= model.nodes.size()) throw InputError(what + ": channel targets a missing node");
        if (c.sampler < 0 || static_cast<size_t>(c.sampler) >= clip.samplers.size()) throw InputError(what + ": channel names a missing sampler");
        channel.node = c.target_node;
        channel.sampler = static_cast<size_t>(c.sampler);
        const Sampler& sampler = clip.samplers[channel.sampler];
        const int want = expected_width(channel.path);
        if (want != 0 && sampler.width() != want) throw InputError(what + ": " + c.target_path + " channel with " + std::to_string(sampler.width()) + " values per key");
        start = std::min(start, sampler.first_time());
        end = std::max(end, sampler.last_time());
        clip.channels.push_back(channel);
    }
    if (clip.channels.empty()) start = end = 0;
    clip.start = start;
    clip.end = end;
    return clip;
}

}  // namespace plumage_host
