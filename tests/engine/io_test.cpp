// VTU frames are read back (a minimal reader of our own binary-appended layout, written from
// the VTK file-format specification) and compared with the particle columns bit for bit;
// atomic writes leave no temporary file behind.
#include <gtest/gtest.h>

#include <cstring>
#include <fstream>
#include <iterator>
#include <limits>
#include <map>
#include <regex>
#include <sstream>

#include "engine/components.hpp"
#include "engine/io.hpp"
#include "engine/simulation.hpp"
#include "test_scenes.hpp"

using namespace sph;

namespace {

struct VtuArrays {
    std::size_t points = 0;
    std::map<std::string, std::vector<char>> arrays;  // name -> raw payload
    std::map<std::string, std::string> types;         // name -> declared VTK type
    double time = -1;                                 // FieldData TimeValue
};

VtuArrays read_vtu(const std::filesystem::path& file) {
    std::ifstream in(file, std::ios::binary);
    std::string all((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    VtuArrays out;
    std::smatch m;
    const std::regex piece("NumberOfPoints=\"(\\d+)\"");
    if (std::regex_search(all, m, piece)) out.points = std::stoul(m[1]);
    const std::size_t data = all.find("<AppendedData encoding=\"raw\">");
    const std::size_t base = all.find('_', data) + 1;
    const std::regex arr("type=\"(\\w+)\" Name=\"([a-z_]+)\"[^>]*offset=\"(\\d+)\"");
    const std::regex time("Name=\"TimeValue\"[^>]*>([^<]+)<");
    if (std::regex_search(all, m, time)) out.time = std::stod(m[1]);
    const std::string header = all.substr(0, data);
    for (auto it = std::sregex_iterator(header.begin(), header.end(), arr); it != std::sregex_iterator(); ++it) {
        // header_type="UInt64": each block starts with its byte count as 8 bytes.
        const std::size_t off = base + std::stoul((*it)[3]);
        std::uint64_t len = 0;
        std::memcpy(&len, all.data() + off, sizeof len);
        out.arrays[(*it)[2]] = std::vector<char>(all.begin() + long(off + 8), all.begin() + long(off + 8 + len));
        out.types[(*it)[2]] = (*it)[1];
    }
    return out;
}

}  // namespace

TEST(Vtu, ReadBackEqualsColumns) {
    Scene s = test::tank_scene(Vec3d(0.1, 0.1, 0.1), Vec3d(0.2, 0.2, 0.2));
    World w;
    initialise_world(w, s);
    w.fluid.store.add(comp::density);
    w.fluid.store.add(comp::pressure);
    auto rho = w.fluid.store.get(comp::density);
    auto v = w.fluid.store.get(comp::velocity);
    for (std::size_t i = 0; i < rho.size(); ++i) {
        rho[i] = Real(1000 + i);
        v[i] = Vec3(Real(i), -Real(i), Real(0.5));
    }
    const auto dir = std::filesystem::temp_directory_path() / "sph_io_test";
    std::filesystem::remove_all(dir);
    const auto file = dir / "frame.vtu";
    write_vtu(file, w, {"velocity", "density", "pressure", "not_a_column"});
    const VtuArrays a = read_vtu(file);
    const std::size_t n = w.fluid.size();
    ASSERT_EQ(a.points, n);
    ASSERT_EQ(a.arrays.count("position"), 1u);
    ASSERT_EQ(a.arrays.at("position").size(), 3 * n * sizeof(Real));
    ASSERT_EQ(a.arrays.at("density").size(), n * sizeof(Real));
    ASSERT_EQ(a.arrays.count("not_a_column"), 0u);
    // Constant/global stepping registers no per-particle step: the frame must not invent one.
    EXPECT_EQ(a.arrays.count("dt"), 0u);
    EXPECT_EQ(a.arrays.count("active"), 0u);
    const auto x = w.fluid.store.get(comp::position);
    const Real* px = reinterpret_cast<const Real*>(a.arrays.at("position").data());
    const Real* pv = reinterpret_cast<const Real*>(a.arrays.at("velocity").data());
    const Real* pr = reinterpret_cast<const Real*>(a.arrays.at("density").data());
    const auto* id = reinterpret_cast<const std::uint32_t*>(a.arrays.at("id").data());
    for (std::size_t i = 0; i < n; ++i) {
        for (int c = 0; c < 3; ++c) {
            EXPECT_EQ(px[3 * i + c], x[i][c]);
            EXPECT_EQ(pv[3 * i + c], v[i][c]);
        }
        EXPECT_EQ(pr[i], rho[i]);
        EXPECT_EQ(id[i], w.fluid.store.get(comp::id)[i]);
    }
    // Connectivity: one vertex cell per point.
    EXPECT_EQ(a.arrays.at("types").size(), n);
    // Atomic write: nothing but the file itself is left in the directory.
    std::size_t files = 0;
    for (const auto& e : std::filesystem::directory_iterator(dir)) {
        ++files;
        EXPECT_EQ(e.path().filename(), "frame.vtu");
    }
    EXPECT_EQ(files, 1u);
    std::filesystem::remove_all(dir);
}

// Individual stepping's columns: Delta t_i is a double and active a byte; both must come back
// byte for byte (including values a float would round or flush: 1e-300, a subnormal, -0, NaN
// bits), with their own VTK types and block sizes, and the arrays after the 1-byte-per-point
// block must still be found at their offsets.
TEST(Vtu, DoubleAndByteColumnsRoundTripByteExact) {
    Scene s = test::tank_scene(Vec3d(0.1, 0.1, 0.1), Vec3d(0.2, 0.2, 0.2));
    World w;
    initialise_world(w, s);
    auto dt = w.fluid.store.add(comp::dt);
    auto active = w.fluid.store.add(comp::active);
    const std::size_t n = w.fluid.size();
    ASSERT_GT(n, 8u);
    const double specials[] = {1e-300, 4.9406564584124654e-324, -0.0, std::numeric_limits<double>::quiet_NaN(),
                               std::numeric_limits<double>::max(), 1.0 / 3.0};
    for (std::size_t i = 0; i < n; ++i) {
        dt[i] = i < std::size(specials) ? specials[i] : 1e-4 * (1.0 + double(i) / 7.0);
        active[i] = std::uint8_t((i * 37 + 1) % 256);
    }
    w.step.t_ticks = 433333333333;  // 0.433333333333 s: the frame time must keep every digit
    w.step.t = to_seconds(w.step.t_ticks);
    const auto dir = std::filesystem::temp_directory_path() / "sph_io_test_individual";
    std::filesystem::remove_all(dir);
    const auto file = dir / "frame.vtu";
    write_vtu(file, w, {"density", "dt", "active"});  // density not registered here: skipped
    const VtuArrays a = read_vtu(file);
    ASSERT_EQ(a.types.at("dt"), "Float64");
    ASSERT_EQ(a.types.at("active"), "UInt8");
    ASSERT_EQ(a.arrays.at("dt").size(), n * sizeof(double));
    ASSERT_EQ(a.arrays.at("active").size(), n);
    EXPECT_EQ(std::memcmp(a.arrays.at("dt").data(), dt.data(), n * sizeof(double)), 0);
    EXPECT_EQ(std::memcmp(a.arrays.at("active").data(), active.data(), n), 0);
    const auto ids = w.fluid.store.get(comp::id);
    const auto x = w.fluid.store.get(comp::position);
    ASSERT_EQ(a.arrays.at("id").size(), n * sizeof(std::uint32_t));
    EXPECT_EQ(std::memcmp(a.arrays.at("id").data(), ids.data(), n * sizeof(std::uint32_t)), 0);
    const Real* px = reinterpret_cast<const Real*>(a.arrays.at("position").data());
    for (std::size_t i = 0; i < n; ++i)
        for (int c = 0; c < 3; ++c) ASSERT_EQ(px[3 * i + c], x[i][c]);
    EXPECT_EQ(a.time, w.step.t);
    std::filesystem::remove_all(dir);
}
