/// @file motion.cpp
/// @brief Analytic displacement and velocity of the kinematic motions (see motion.hpp).
#include "engine/data/motion.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include <Eigen/Geometry>

namespace sph {

const char* to_string(MotionType t) {
    switch (t) {
        case MotionType::Linear:
            return "linear";
        case MotionType::Sinusoidal:
            return "sinusoidal";
        case MotionType::Path:
            return "path";
        case MotionType::Circle:
            return "circle";
    }
    return "unknown";
}

namespace {

/// Where a path is at time t: the segment k (from vertex k to vertex k + 1, modulo the vertex
/// count when looping), the arc length into it, and whether the body has stopped at the end.
struct PathPoint {
    std::size_t k = 0;
    double into = 0;
    bool stopped = false;
};

std::size_t path_segments(const Motion& m) {
    return m.loop ? m.points.size() : m.points.size() - 1;
}
const Vec3d& vertex(const Motion& m, std::size_t k) {
    return m.points[k % m.points.size()];
}

double path_length(const Motion& m) {
    double total = 0;
    for (std::size_t k = 0; k < path_segments(m); ++k) total += (vertex(m, k + 1) - vertex(m, k)).norm();
    return total;
}

PathPoint locate(const Motion& m, double t) {
    const double total = path_length(m);
    double s = std::max(0.0, m.speed * t);
    PathPoint p;
    if (!(total > 0)) return {0, 0, true};
    if (m.loop) {
        s = std::fmod(s, total);
    } else if (s >= total) {
        p.k = path_segments(m) - 1;
        p.into = (vertex(m, p.k + 1) - vertex(m, p.k)).norm();
        p.stopped = true;
        return p;
    }
    for (std::size_t k = 0; k < path_segments(m); ++k) {
        const double len = (vertex(m, k + 1) - vertex(m, k)).norm();
        if (s < len || k + 1 == path_segments(m)) {
            p.k = k;
            p.into = std::min(s, len);
            return p;
        }
        s -= len;
    }
    return p;
}

}  // namespace

Vec3d displacement(const Motion& m, double t) {
    switch (m.type) {
        case MotionType::Linear:
            return m.velocity * t;
        case MotionType::Sinusoidal:
            return m.amplitude * std::sin(2.0 * std::numbers::pi * t / m.period + m.phase) * m.axis;
        case MotionType::Path: {
            const PathPoint p = locate(m, t);
            const Vec3d a = vertex(m, p.k), b = vertex(m, p.k + 1);
            const double len = (b - a).norm();
            const Vec3d at = len > 0 ? Vec3d(a + (p.into / len) * (b - a)) : a;
            return at - m.points.front();
        }
        case MotionType::Circle: {
            const double wt = m.speed / m.radius * t;
            const Vec3d w = m.axis.cross(m.start);
            return m.radius * ((std::cos(wt) - 1.0) * m.start + std::sin(wt) * w);
        }
    }
    return Vec3d::Zero();
}

Vec3d velocity(const Motion& m, double t) {
    switch (m.type) {
        case MotionType::Linear:
            return m.velocity;
        case MotionType::Sinusoidal: {
            const double omega = 2.0 * std::numbers::pi / m.period;
            return m.amplitude * omega * std::cos(omega * t + m.phase) * m.axis;
        }
        case MotionType::Path: {
            const PathPoint p = locate(m, t);
            if (p.stopped) return Vec3d::Zero();
            const Vec3d seg = vertex(m, p.k + 1) - vertex(m, p.k);
            const double len = seg.norm();
            return len > 0 ? Vec3d(m.speed / len * seg) : Vec3d::Zero();
        }
        case MotionType::Circle: {
            const double wt = m.speed / m.radius * t;
            const Vec3d w = m.axis.cross(m.start);
            return m.speed * (-std::sin(wt) * m.start + std::cos(wt) * w);
        }
    }
    return Vec3d::Zero();
}

double speed_bound(const Motion& m, double t) {
    switch (m.type) {
        case MotionType::Linear:
            return m.velocity.norm();
        case MotionType::Sinusoidal:
            return 2.0 * std::numbers::pi * std::abs(m.amplitude) / m.period;
        case MotionType::Path:
            return locate(m, t).stopped ? 0.0 : m.speed;
        case MotionType::Circle:
            return m.speed;
    }
    return 0.0;
}

std::pair<Vec3d, Vec3d> displacement_bounds(const Motion& m, double t_end) {
    Vec3d lo = Vec3d::Zero(), hi = Vec3d::Zero();
    auto grow = [&](const Vec3d& d) {
        lo = lo.cwiseMin(d);
        hi = hi.cwiseMax(d);
    };
    switch (m.type) {
        case MotionType::Linear:
            grow(m.velocity * t_end);
            break;
        case MotionType::Sinusoidal:
            grow(-std::abs(m.amplitude) * m.axis.cwiseAbs());
            grow(std::abs(m.amplitude) * m.axis.cwiseAbs());
            break;
        case MotionType::Path:
            for (const Vec3d& p : m.points) grow(p - m.points.front());
            break;
        case MotionType::Circle: {
            // Circle points c + R (cos a u + sin a w): component k spans c_k +- R sqrt(u_k^2 + w_k^2).
            const Vec3d w = m.axis.cross(m.start);
            const Vec3d start = m.center + m.radius * m.start;
            for (int k = 0; k < 3; ++k) {
                const double half = m.radius * std::hypot(m.start[k], w[k]);
                Vec3d d = Vec3d::Zero();
                d[k] = m.center[k] - half - start[k];
                grow(d);
                d[k] = m.center[k] + half - start[k];
                grow(d);
            }
            break;
        }
    }
    return {lo, hi};
}

Motion linear_motion(const Vec3d& velocity) {
    Motion m;
    m.type = MotionType::Linear;
    m.velocity = velocity;
    return m;
}

Motion sinusoidal_motion(const Vec3d& axis, double amplitude, double period, double phase) {
    Motion m;
    m.type = MotionType::Sinusoidal;
    m.axis = unit(axis);
    m.amplitude = amplitude;
    m.period = period;
    m.phase = phase;
    return m;
}

Motion path_motion(std::vector<Vec3d> points, double speed, bool loop) {
    Motion m;
    m.type = MotionType::Path;
    m.points = std::move(points);
    m.speed = speed;
    m.loop = loop;
    return m;
}

Motion circle_motion(const Vec3d& center, double radius, const Vec3d& axis, double speed,
                     const Vec3d& start_point) {
    Motion m;
    m.type = MotionType::Circle;
    m.center = center;
    m.radius = radius;
    m.axis = unit(axis);
    m.speed = speed;
    const Vec3d rel = start_point - center;
    m.start = unit(rel - rel.dot(m.axis) * m.axis);
    return m;
}

}  // namespace sph
