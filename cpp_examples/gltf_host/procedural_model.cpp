#include "procedural_model.h"

#include <algorithm>
#include <cmath>

namespace plumage_host {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kLength = 4.0;
constexpr double kRadius = 0.45;
constexpr double kWavelength = 0.8;  // in units of body length
constexpr double kPeriod = 1.0;      // seconds

// Body radius at u in [0, 1]: closed at both ends, fuller toward the head.
double radius(double u) { return kRadius * std::sqrt(std::sin(kPi * u)) * (1.0 - 0.5 * u); }

// Sideways amplitude: small at the head, large at the tail.
double amplitude(double u) { return 0.05 + 0.35 * u * u; }
double amplitude_slope(double u) { return 0.7 * u; }

// The wave fades in smoothly over the first half second.
double envelope(double t) {
    const double s = std::clamp(t / 0.5, 0.0, 1.0);
    return s * s * (3 - 2 * s);
}

}  // namespace

ProceduralBody::ProceduralBody(int rings, int segments) : rings_(std::max(rings, 3)), segments_(std::max(segments, 3)) {
    // Counter-clockwise seen from outside. Vertices: rings 1 .. rings-1 of (segments + 1) each (seam duplicated), then the two poles.
    const uint32_t ring_size = static_cast<uint32_t>(segments_ + 1);
    const auto vertex = [&](int ring, int seg) { return static_cast<uint32_t>(ring - 1) * ring_size + static_cast<uint32_t>(seg); };
    const uint32_t head = static_cast<uint32_t>(rings_ - 1) * ring_size, tail = head + 1;
    for (int i = 1; i + 1 < rings_; ++i) {
        for (int j = 0; j < segments_; ++j) {
            const uint32_t a = vertex(i, j), b = vertex(i, j + 1);
            if (i == 1) indices_.insert(indices_.end(), {head, a, b});
            if (i + 2 < rings_) {
                const uint32_t c = vertex(i + 1, j), d = vertex(i + 1, j + 1);
                indices_.insert(indices_.end(), {a, c, d, a, d, b});
            } else {
                indices_.insert(indices_.end(), {a, tail, b});
            }
        }
    }
    pose_at(0.0, rest_);
}

void ProceduralBody::pose_at(double t, std::vector<float>& xyz) const {
    const double env = envelope(t);
    const size_t ring_size = static_cast<size_t>(segments_ + 1);
    xyz.assign((static_cast<size_t>(rings_ - 1) * ring_size + 2) * 3, 0.0f);
    // Centre line (x, 0, w(u)) and its unit tangent in the x-z plane.
    const auto centre = [&](double u, double& x, double& w, double& tx, double& tz) {
        const double phase = 2 * kPi * (u / kWavelength - t / kPeriod);
        x = kLength * u;
        w = env * amplitude(u) * std::sin(phase);
        const double dw = env * (amplitude_slope(u) * std::sin(phase) + amplitude(u) * std::cos(phase) * 2 * kPi / kWavelength);
        const double n = std::hypot(kLength, dw);
        tx = kLength / n, tz = dw / n;
    };
    double x, w, tx, tz;
    for (int i = 1; i + 1 < rings_; ++i) {
        const double u = static_cast<double>(i) / rings_;
        centre(u, x, w, tx, tz);
        const double r = radius(u);
        for (int j = 0; j <= segments_; ++j) {
            const double phi = 2 * kPi * (j % segments_) / segments_;
            const double side = r * std::cos(phi), up = 0.8 * r * std::sin(phi);  // slightly flattened
            // The cross-section stays perpendicular to the bent centre line: side axis (-tz, 0, tx).
            const size_t v = (static_cast<size_t>(i - 1) * ring_size + static_cast<size_t>(j)) * 3;
            xyz[v] = static_cast<float>(x - side * tz);
            xyz[v + 1] = static_cast<float>(up);
            xyz[v + 2] = static_cast<float>(w + side * tx);
        }
    }
    const size_t poles = static_cast<size_t>(rings_ - 1) * ring_size * 3;
    for (int end = 0; end < 2; ++end) {
        centre(end, x, w, tx, tz);
        xyz[poles + 3 * static_cast<size_t>(end)] = static_cast<float>(x);
        xyz[poles + 3 * static_cast<size_t>(end) + 2] = static_cast<float>(w);
    }
}

}  // namespace plumage_host
