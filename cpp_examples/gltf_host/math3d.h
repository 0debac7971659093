// Small double-precision vector, quaternion and matrix helpers for glTF
// evaluation. Matrices are column-major, as glTF stores them.
#pragma once

#include <array>
#include <cmath>

namespace plumage_host {

struct Vec3 {
    double x = 0, y = 0, z = 0;
};

// Unit quaternion (x, y, z, w), glTF's order.
struct Quat {
    double x = 0, y = 0, z = 0, w = 1;
};

// Column-major 4x4: element (row r, column c) is m[c * 4 + r].
struct Mat4 {
    std::array<double, 16> m{1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};

    double at(int row, int col) const { return m[static_cast<size_t>(col * 4 + row)]; }
    double& at(int row, int col) { return m[static_cast<size_t>(col * 4 + row)]; }
};

inline Mat4 operator*(const Mat4& a, const Mat4& b) {
    Mat4 r;
    for (int c = 0; c < 4; ++c) {
        for (int row = 0; row < 4; ++row) {
            double s = 0;
            for (int k = 0; k < 4; ++k) s += a.at(row, k) * b.at(k, c);
            r.at(row, c) = s;
        }
    }
    return r;
}

inline Mat4 operator*(double s, const Mat4& a) {
    Mat4 r = a;
    for (double& v : r.m) v *= s;
    return r;
}

inline Mat4 operator+(const Mat4& a, const Mat4& b) {
    Mat4 r = a;
    for (size_t i = 0; i < 16; ++i) r.m[i] += b.m[i];
    return r;
}

inline Vec3 transform_point(const Mat4& a, const Vec3& p) {
    return {a.at(0, 0) * p.x + a.at(0, 1) * p.y + a.at(0, 2) * p.z + a.at(0, 3),
            a.at(1, 0) * p.x + a.at(1, 1) * p.y + a.at(1, 2) * p.z + a.at(1, 3),
            a.at(2, 0) * p.x + a.at(2, 1) * p.y + a.at(2, 2) * p.z + a.at(2, 3)};
}

inline Quat normalized(const Quat& q) {
    const double n = std::sqrt(q.x * q.x + q.y * q.y + q.z * q.z + q.w * q.w);
    if (!(n > 0) || !std::isfinite(n)) return Quat{};
    return {q.x / n, q.y / n, q.z / n, q.w / n};
}

// Spherical interpolation along the shorter arc: q and -q are the same
// rotation, so b is flipped when the two lie in opposite hemispheres.
inline Quat slerp(const Quat& a, Quat b, double u) {
    double d = a.x * b.x + a.y * b.y + a.z * b.z + a.w * b.w;
    if (d < 0) {
        b = {-b.x, -b.y, -b.z, -b.w};
        d = -d;
    }
    double wa = 1 - u, wb = u;
    if (d < 0.9995) {  // otherwise nearly parallel: a normalized lerp is exact enough
        const double theta = std::acos(d);
        const double s = std::sin(theta);
        wa = std::sin((1 - u) * theta) / s;
        wb = std::sin(u * theta) / s;
    }
    return normalized({wa * a.x + wb * b.x, wa * a.y + wb * b.y, wa * a.z + wb * b.z, wa * a.w + wb * b.w});
}

// T * R * S, the glTF node transform.
inline Mat4 compose_trs(const Vec3& t, const Quat& q_in, const Vec3& s) {
    const Quat q = normalized(q_in);
    const double xx = q.x * q.x, yy = q.y * q.y, zz = q.z * q.z;
    const double xy = q.x * q.y, xz = q.x * q.z, yz = q.y * q.z;
    const double wx = q.w * q.x, wy = q.w * q.y, wz = q.w * q.z;
    Mat4 r;
    r.at(0, 0) = (1 - 2 * (yy + zz)) * s.x;
    r.at(1, 0) = 2 * (xy + wz) * s.x;
    r.at(2, 0) = 2 * (xz - wy) * s.x;
    r.at(0, 1) = 2 * (xy - wz) * s.y;
    r.at(1, 1) = (1 - 2 * (xx + zz)) * s.y;
    r.at(2, 1) = 2 * (yz + wx) * s.y;
    r.at(0, 2) = 2 * (xz + wy) * s.z;
    r.at(1, 2) = 2 * (yz - wx) * s.z;
    r.at(2, 2) = (1 - 2 * (xx + yy)) * s.z;
    r.at(0, 3) = t.x;
    r.at(1, 3) = t.y;
    r.at(2, 3) = t.z;
    return r;
}

}  // namespace plumage_host
