#pragma once
/// @file motion.hpp
/// @brief Kinematic (prescribed) rigid motions of boundaries: pure translations d(t), given
/// analytically together with their velocity v(t) = d'(t). SI units: metres, seconds,
/// radians. A moving boundary's particle at rest position x0 is at x0 + d(t) at time t.
#include <utility>
#include <vector>

#include "engine/core/types.hpp"

namespace sph {

enum class MotionType { Linear, Sinusoidal, Path, Circle };

/// @brief Names as written in scene files (`"linear"`, `"sinusoidal"`, `"path"`, `"circle"`).
const char* to_string(MotionType t);

/// @brief A prescribed translation. Only the fields of its `type` are used:
/// * `linear`:     d(t) = velocity t.
/// * `sinusoidal`: d(t) = amplitude sin(2 pi t / period + phase) axis. The declared geometry is
///   the centre of the oscillation, so with a phase the body starts displaced by
///   amplitude sin(phase) axis.
/// * `path`:       the body's declared position is at points[0]; it is translated along the
///   polyline at constant `speed`, d(t) = P(speed t) - points[0] with P(s) the point at arc
///   length s. At the end it stops at the last point (v = 0) unless `loop`, which closes the
///   polyline with a segment from the last point back to the first and goes round forever.
/// * `circle`:     the body is translated (not rotated) so that its reference point runs round
///   the circle of `center`, `radius` in the plane normal to `axis`, at `speed`, counter-
///   clockwise seen from the tip of `axis`: d(t) = radius((cos wt - 1) u + sin wt (axis x u)),
///   w = speed / radius, with u the unit vector from `center` to the start point (`start`).
struct Motion {
    MotionType type = MotionType::Linear;
    Vec3d velocity{0, 0, 0};     ///< linear: m/s
    Vec3d axis{0, 1, 0};         ///< sinusoidal: unit direction; circle: unit plane normal
    double amplitude = 0;        ///< sinusoidal: m
    double period = 1;           ///< sinusoidal: s, > 0
    double phase = 0;            ///< sinusoidal: rad
    std::vector<Vec3d> points;   ///< path: m, at least 2, consecutive points distinct
    bool loop = false;           ///< path
    double speed = 0;            ///< path, circle: m/s along the path, > 0
    Vec3d center{0, 0, 0};       ///< circle: m
    double radius = 0;           ///< circle: m, > 0
    Vec3d start{1, 0, 0};        ///< circle: unit vector u from center to the start, in the plane
    bool operator==(const Motion&) const = default;
};

/// @brief d(t) in metres (t in seconds, t >= 0).
Vec3d displacement(const Motion& m, double t);
/// @brief v(t) = d'(t) in m/s. On a path's vertex, the velocity of the segment being entered.
Vec3d velocity(const Motion& m, double t);
/// @brief An upper bound on |v(s)| for every s >= t, m/s (the wake rule of individual stepping
/// uses it to bound how far the body can move before a particle's next evaluation).
double speed_bound(const Motion& m, double t);
/// @brief Componentwise (min, max) of d(t) over t in [0, t_end], m (exact or conservative).
std::pair<Vec3d, Vec3d> displacement_bounds(const Motion& m, double t_end);

/// @brief Motions built in code (tests, tools); the loader builds the same from JSON.
Motion linear_motion(const Vec3d& velocity);
/// @warning `axis` must be non-zero (it is normalised); `period` > 0.
Motion sinusoidal_motion(const Vec3d& axis, double amplitude, double period, double phase = 0);
/// @warning at least 2 points, consecutive points distinct, `speed` > 0.
Motion path_motion(std::vector<Vec3d> points, double speed, bool loop);
/// @brief A circle whose start is the point of the circle in the direction of `start_point`
/// (the body's reference point) seen from `center`, projected on the plane.
/// @warning `axis` non-zero, `radius` > 0, `speed` > 0; `start_point` off the axis line.
Motion circle_motion(const Vec3d& center, double radius, const Vec3d& axis, double speed,
                     const Vec3d& start_point);

}  // namespace sph
