// The engine example's own deforming mesh: a capsule (a game character's
// limb) of 4 992 triangles along +x, waving with a sine that travels from
// its root to its tip, bent as a skinned limb bends: each cross-section
// turns with the centre line, so the skin keeps its shape.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

namespace engine {

// Which part of the limb moves.
enum class Wave {
    Whole,    // everything: the root swings too, like a limb from its shoulder
    FarHalf,  // the near half (s <= length / 2) and its cap stay exactly at rest
};

struct Capsule {
    float length = 4.0f;  // of the cylinder, from x = 0 to x = length
    float radius = 0.5f;
    std::vector<float> rest;        // xyz per vertex
    std::vector<uint32_t> indices;  // three per triangle, facing outwards

    size_t vertex_count() const { return rest.size() / 3; }
    size_t triangle_count() const { return indices.size() / 3; }
};

// SEGMENTS vertices around each ring; CAP_RINGS rings on each hemisphere (the
// last at the cylinder's end), BODY_RINGS - 1 rings inside the cylinder, and
// a pole at each end: 2·SEGMENTS·(2·CAP_RINGS + BODY_RINGS - 1) triangles.
constexpr int SEGMENTS = 32;
constexpr int CAP_RINGS = 8;
constexpr int BODY_RINGS = 63;

inline Capsule make_capsule() {
    const double pi = 3.14159265358979323846;
    Capsule c;
    const double r = c.radius, len = c.length;
    std::vector<double> ring_x, ring_r;  // ring profile from the near pole to the far pole
    for (int i = 1; i <= CAP_RINGS; ++i) {
        const double phi = 0.5 * pi * i / CAP_RINGS;
        ring_x.push_back(-r * std::cos(phi));
        ring_r.push_back(r * std::sin(phi));
    }
    for (int j = 1; j < BODY_RINGS; ++j) {
        ring_x.push_back(len * j / BODY_RINGS);
        ring_r.push_back(r);
    }
    for (int i = CAP_RINGS; i >= 1; --i) {
        const double phi = 0.5 * pi * i / CAP_RINGS;
        ring_x.push_back(len + r * std::cos(phi));
        ring_r.push_back(r * std::sin(phi));
    }
    const uint32_t rings = static_cast<uint32_t>(ring_x.size());
    auto push = [&c](double x, double y, double z) {
        c.rest.push_back(static_cast<float>(x));
        c.rest.push_back(static_cast<float>(y));
        c.rest.push_back(static_cast<float>(z));
    };
    push(-r, 0.0, 0.0);
    for (uint32_t i = 0; i < rings; ++i) {
        for (int j = 0; j < SEGMENTS; ++j) {
            const double ph = 2.0 * pi * j / SEGMENTS;
            push(ring_x[i], ring_r[i] * std::cos(ph), ring_r[i] * std::sin(ph));
        }
    }
    push(len + r, 0.0, 0.0);
    const uint32_t near_pole = 0, far_pole = 1 + rings * SEGMENTS;
    auto at = [](uint32_t ring, uint32_t seg) { return 1 + ring * SEGMENTS + seg % SEGMENTS; };
    auto tri = [&c](uint32_t a, uint32_t b, uint32_t d) {
        c.indices.insert(c.indices.end(), {a, b, d});
    };
    for (uint32_t j = 0; j < SEGMENTS; ++j) {
        tri(near_pole, at(0, j + 1), at(0, j));
        for (uint32_t i = 0; i + 1 < rings; ++i) {
            const uint32_t a = at(i, j), b = at(i, j + 1), d = at(i + 1, j), e = at(i + 1, j + 1);
            tri(a, b, d);
            tri(d, b, e);
        }
        tri(at(rings - 1, j), at(rings - 1, j + 1), far_pole);
    }
    return c;
}

// The limb's pose at time t (seconds): the centre line bends by the angle
// theta(s, t) = amplitude(s) · e(t) · sin(ω t − k s) in the xy plane
// (amplitude 0.5 rad at the tip, a 2 s period, a wavelength of 4/3 of the
// length; e eases in over the first 0.25 s, so t = 0 is the rest pose). A
// vertex at (x, y, z) of the rest capsule sits at arc length s = clamp(x, 0,
// length) on the centre line C(s) = ∫ (cos θ, sin θ, 0); its offset (x − s,
// y) turns by θ(s), z stays. With Wave::FarHalf θ is exactly 0 for s <=
// length / 2, so that half's positions are bit for bit the rest pose's.
class Limb {
public:
    explicit Limb(const Capsule& body, Wave wave) : body_(body), wave_(wave) {}

    void pose(double t, std::vector<float>& out) {
        const double pi = 3.14159265358979323846;
        const double len = body_.length;
        const double omega = 2.0 * pi / 2.0, k = 2.0 * pi / (len * 4.0 / 3.0), amplitude = 0.5;
        const double ease = std::min(1.0, t / 0.25);
        const double e = ease * ease * (3.0 - 2.0 * ease);
        auto theta = [&](double s) {
            double a;
            if (wave_ == Wave::Whole) {
                a = amplitude * (0.3 + 0.7 * s / len);
            } else {
                a = s <= 0.5 * len ? 0.0 : amplitude * (s - 0.5 * len) / (0.5 * len);
            }
            return a == 0.0 ? 0.0 : a * e * std::sin(omega * t - k * s);
        };
        // The centre line at STEPS + 1 evenly spaced nodes (midpoint rule).
        constexpr int STEPS = 512;
        const double h = len / STEPS;
        cx_.assign(STEPS + 1, 0.0);
        cy_.assign(STEPS + 1, 0.0);
        for (int i = 0; i < STEPS; ++i) {
            const double th = theta((i + 0.5) * h);
            cx_[i + 1] = cx_[i] + h * std::cos(th);
            cy_[i + 1] = cy_[i] + h * std::sin(th);
        }
        out.resize(body_.rest.size());
        for (size_t v = 0; v < body_.vertex_count(); ++v) {
            const double x = body_.rest[3 * v], y = body_.rest[3 * v + 1], z = body_.rest[3 * v + 2];
            const double s = std::clamp(x, 0.0, len);
            const double f = s / h;
            const int i = std::min(static_cast<int>(f), STEPS - 1);
            const double w = f - i;
            const double px = cx_[i] + w * (cx_[i + 1] - cx_[i]);
            const double py = cy_[i] + w * (cy_[i + 1] - cy_[i]);
            const double th = theta(s), c = std::cos(th), sn = std::sin(th);
            const double u = x - s;
            out[3 * v] = static_cast<float>(px + u * c - y * sn);
            out[3 * v + 1] = static_cast<float>(py + u * sn + y * c);
            out[3 * v + 2] = static_cast<float>(z);
        }
    }

private:
    const Capsule& body_;
    Wave wave_;
    std::vector<double> cx_, cy_;
};

}  // namespace engine
