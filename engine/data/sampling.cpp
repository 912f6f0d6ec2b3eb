#include "engine/data/sampling.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <unordered_map>

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

BlockFill block_fill(const Aabb& box, double spacing) {
    BlockFill f;
    f.particles = lattice_dims(box, spacing).cwiseMax(0);
    const Vec3d extent = box.max - box.min;
    f.declared_volume = extent.prod();
    f.particle_volume = double(f.particles.x()) * f.particles.y() * f.particles.z() * spacing * spacing * spacing;
    return f;
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

// Ihmsen 2010 sec. 3.4 samples boundaries "close to uniform" at the rest spacing. Each triangle
// is sampled on its own barycentric lattice of n x n sub-triangles, n = ceil(longest edge / s),
// so no two neighbouring samples of a triangle are farther apart than s; samples shared by
// adjacent triangles (edges, vertices) are merged (positions within s / 4) and their normals
// averaged. Samples sit `offset` behind the front face (along -n).
SurfaceSamples triangle_surface(const std::vector<Vec3d>& v, const std::vector<std::array<int, 3>>& tris,
                                double spacing, double offset) {
    std::vector<Vec3d> pos, nrm;
    std::unordered_map<std::uint64_t, std::vector<std::size_t>> cells;
    const double cell = 0.25 * spacing;
    auto key = [&](const Vec3d& p) {
        const auto q = [&](double x) { return std::uint64_t(std::int64_t(std::floor(x / cell)) & 0x1FFFFF); };
        return q(p.x()) | (q(p.y()) << 21) | (q(p.z()) << 42);
    };
    auto add = [&](const Vec3d& p, const Vec3d& n) {
        const Eigen::Vector3d c = (p / cell).array().floor();
        for (int dz = -1; dz <= 1; ++dz)
            for (int dy = -1; dy <= 1; ++dy)
                for (int dx = -1; dx <= 1; ++dx) {
                    auto it = cells.find(key((c + Eigen::Vector3d(dx, dy, dz)) * cell + Vec3d::Constant(0.5 * cell)));
                    if (it == cells.end()) continue;
                    for (std::size_t k : it->second)
                        if ((pos[k] - p).norm() < cell) {
                            nrm[k] += n;
                            return;
                        }
                }
        cells[key(p)].push_back(pos.size());
        pos.push_back(p);
        nrm.push_back(n);
    };
    for (const auto& t : tris) {
        const std::array<Vec3d, 3> p{v[t[0]], v[t[1]], v[t[2]]};
        const Vec3d cr = (p[1] - p[0]).cross(p[2] - p[0]);
        if (cr.norm() <= 0) continue;  // degenerate
        const Vec3d n = cr.normalized();
        // Lattice spanned by the two edges at the vertex opposite the longest edge (its angle is
        // the largest, >= 60 degrees), ceil(|edge| / s) steps along each: spacing <= s on both.
        int k = 0;  // vertex k is opposite the edge (k+1, k+2)
        double longest = -1;
        for (int e = 0; e < 3; ++e) {
            const double len = (p[(e + 1) % 3] - p[(e + 2) % 3]).norm();
            if (len > longest) longest = len, k = e;
        }
        const Vec3d a = p[k], b = p[(k + 1) % 3], c = p[(k + 2) % 3];
        const int nb = std::max(1, int(std::ceil((b - a).norm() / spacing - 1e-9)));
        const int nc = std::max(1, int(std::ceil((c - a).norm() / spacing - 1e-9)));
        for (int i = 0; i <= nb; ++i)
            for (int j = 0; j <= nc; ++j) {
                const double fb = double(i) / nb, fc = double(j) / nc;
                if (fb + fc > 1.0 + 1e-9) continue;
                add(a + fb * (b - a) + fc * (c - a), n);
            }
    }
    SurfaceSamples s;
    for (std::size_t k = 0; k < pos.size(); ++k) {
        const Vec3d n = nrm[k].norm() > 0 ? Vec3d(nrm[k].normalized()) : Vec3d::UnitY();
        s.positions.push_back(pos[k] - offset * n);
        s.normals.push_back(n);
    }
    return s;
}

// A solid capped cylinder: rings on the side every ~s along the axis, each of round(2 pi R / s)
// points, and concentric rings on both caps; all `offset` inside the solid, normals outward.
SurfaceSamples cylinder_surface(const BoundaryDesc& b, double spacing, double offset) {
    SurfaceSamples s;
    const Vec3d ax = b.axis.normalized();
    const Vec3d u = (std::abs(ax.x()) < 0.9 ? Vec3d::UnitX() : Vec3d::UnitY()).cross(ax).normalized();
    const Vec3d w = ax.cross(u);
    const double R = std::max(b.radius - offset, 0.5 * b.radius);
    const double y0 = std::min(offset, 0.5 * b.height), y1 = std::max(b.height - offset, 0.5 * b.height);
    const int rings = std::max(1, int(std::lround((y1 - y0) / spacing)));
    const int around = std::max(6, int(std::lround(2 * std::numbers::pi * R / spacing)));
    for (int k = 0; k <= rings; ++k)
        for (int i = 0; i < around; ++i) {
            const double phi = 2 * std::numbers::pi * (i + 0.5 * (k % 2)) / around;
            const Vec3d radial = std::cos(phi) * u + std::sin(phi) * w;
            s.positions.push_back(b.center + (y0 + (y1 - y0) * k / rings) * ax + R * radial);
            s.normals.push_back(radial);
        }
    for (const bool top : {false, true}) {
        const Vec3d c = b.center + (top ? y1 : y0) * ax;
        const Vec3d n = top ? ax : Vec3d(-ax);
        s.positions.push_back(c);
        s.normals.push_back(n);
        const int circles = int(std::ceil(R / spacing - 1e-9));  // ring spacing R / circles <= s
        for (int k = 1; k <= circles; ++k) {
            if (k == circles) continue;  // the side's end ring is the cap's rim
            const double rho = R * k / circles;
            const int cnt = std::max(6, int(std::lround(2 * std::numbers::pi * rho / spacing)));
            for (int i = 0; i < cnt; ++i) {
                const double phi = 2 * std::numbers::pi * i / cnt;
                s.positions.push_back(c + rho * (std::cos(phi) * u + std::sin(phi) * w));
                s.normals.push_back(n);
            }
        }
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
        case BoundaryShape::Cylinder:
            return cylinder_surface(b, spacing, offset);
        case BoundaryShape::Heightfield:
        case BoundaryShape::Mesh:
            return triangle_surface(b.vertices, b.triangles, spacing, offset);
    }
    return {};
}

}  // namespace sph
