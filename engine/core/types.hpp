#pragma once
/// @file types.hpp
/// @brief Scalar and vector types shared by the whole engine.
#include <Eigen/Core>
#include <cmath>
#include <cstdint>
#include <limits>

namespace sph {

#ifdef SPH_DOUBLE
using Real = double;
#else
/// @brief Particle field precision: float by default, double with SPH_DOUBLE=ON.
using Real = float;
#endif

using Vec3 = Eigen::Matrix<Real, 3, 1>;
/// @brief Double-precision 3-vector for scene geometry and reductions.
using Vec3d = Eigen::Matrix<double, 3, 1>;
using Mat3 = Eigen::Matrix<Real, 3, 3>;
using Index = std::uint32_t;

/// @brief `v` scaled to length 1, and a vector already of length 1 (to 4 ulp of its squared
/// norm) as it is: normalising twice may move a component by an ulp, and a direction written out
/// and read back (scene_to_json, the loader) must come back the same.
inline Vec3d unit(const Vec3d& v) {
    const double n2 = v.squaredNorm();
    return std::abs(n2 - 1.0) <= 4 * std::numeric_limits<double>::epsilon() ? v : Vec3d(v / std::sqrt(n2));
}

/// @brief Axis-aligned box in metres.
struct Aabb {
    Vec3d min{0, 0, 0};
    Vec3d max{0, 0, 0};
    Vec3d extent() const { return max - min; }
    bool contains(const Vec3d& p) const {
        return (p.array() >= min.array()).all() && (p.array() <= max.array()).all();
    }
    bool operator==(const Aabb&) const = default;
};

}  // namespace sph
