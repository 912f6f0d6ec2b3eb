#include "engine/sampling.hpp"

#include <cmath>
#include <numbers>

namespace sph {

std::vector<Vec3d> sample_block(const Aabb& box, double spacing) {
    const Eigen::Vector3i n = lattice_dims(box, spacing);
    std::vector<Vec3d> out;
    out.reserve(std::size_t(std::max(0, n[0])) * std::max(0, n[1]) * std::max(0, n[2]));
    for (int k = 0; k < n[2]; ++k)
        for (int j = 0; j < n[1]; ++j)
            for (int i = 0; i < n[0]; ++i)
                out.push_back(box.min + spacing * Vec3d(i + 0.5, j + 0.5, k + 0.5));
    return out;
}

namespace {

// Points of a box surface lattice (every lattice point with an index on a face), with the
// outward normal (average of the faces it lies on).
SurfaceSamples box_surface(const Aabb& box, double spacing, double normal_sign) {
    SurfaceSamples s;
    Eigen::Vector3i n;
    Vec3d step;
    for (int a = 0; a < 3; ++a) {
        const double len = box.max[a] - box.min[a];
        n[a] = std::max(1, static_cast<int>(std::lround(len / spacing)));
        step[a] = len / n[a];
    }
    for (int k = 0; k <= n[2]; ++k)
        for (int j = 0; j <= n[1]; ++j)
            for (int i = 0; i <= n[0]; ++i) {
                const Eigen::Vector3i c(i, j, k);
                Vec3d normal = Vec3d::Zero();
                for (int a = 0; a < 3; ++a) {
                    if (c[a] == 0) normal[a] -= 1;
                    if (c[a] == n[a]) normal[a] += 1;
                }
                if (normal.squaredNorm() == 0) continue;  // interior point
                s.positions.push_back(box.min + Vec3d(i * step[0], j * step[1], k * step[2]));
                s.normals.push_back(normal_sign * normal.normalized());
            }
    return s;
}

}  // namespace

SurfaceSamples sample_boundary(const BoundaryDesc& b, double spacing, double offset) {
    switch (b.shape) {
        case BoundaryShape::Container: {  // the fluid is inside: samples outside the box
            const Aabb grown{b.box.min - Vec3d::Constant(offset), b.box.max + Vec3d::Constant(offset)};
            return box_surface(grown, spacing, -1.0);
        }
        case BoundaryShape::Box: {  // solid: samples inside it
            Aabb shrunk{b.box.min + Vec3d::Constant(offset), b.box.max - Vec3d::Constant(offset)};
            for (int a = 0; a < 3; ++a)
                if (shrunk.min[a] > shrunk.max[a]) shrunk.min[a] = shrunk.max[a] = 0.5 * (b.box.min[a] + b.box.max[a]);
            return box_surface(shrunk, spacing, 1.0);
        }
        case BoundaryShape::Sphere: {
            SurfaceSamples s;
            const double radius = std::max(b.radius - offset, 0.5 * b.radius);
            const double area = 4.0 * std::numbers::pi * radius * radius;
            const int count = std::max(12, static_cast<int>(std::lround(area / (spacing * spacing))));
            const double golden = std::numbers::pi * (3.0 - std::sqrt(5.0));
            for (int i = 0; i < count; ++i) {
                const double y = 1.0 - 2.0 * (i + 0.5) / count;
                const double rad = std::sqrt(std::max(0.0, 1.0 - y * y));
                const double phi = golden * i;
                const Vec3d nrm(std::cos(phi) * rad, y, std::sin(phi) * rad);
                s.positions.push_back(b.center + radius * nrm);
                s.normals.push_back(nrm);
            }
            return s;
        }
    }
    return {};
}

}  // namespace sph
