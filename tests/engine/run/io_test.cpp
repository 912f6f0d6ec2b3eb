// VTU frames are read back (a minimal reader of our own binary-appended layout, written from
// the VTK file-format specification) and compared with the particle columns bit for bit;
// atomic writes leave no temporary file behind.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <fstream>
#include <iterator>
#include <limits>
#include <map>
#include <random>
#include <regex>
#include <sstream>

#include "engine/data/components.hpp"
#include "engine/run/io.hpp"
#include "engine/run/simulation.hpp"
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
    w.clock.t_ticks = 433333333333;  // 0.433333333333 s: the frame time must keep every digit
    w.clock.t = to_seconds(w.clock.t_ticks);
    const auto dir = std::filesystem::temp_directory_path() / "sph_io_test_individual";
    std::filesystem::remove_all(dir);
    const auto file = dir / "frame.vtu";
    write_vtu(file, w, {"density", "dt", "active", "bin"});  // density, bin not registered: skipped
    {
        const VtuArrays none = read_vtu(file);
        EXPECT_EQ(none.arrays.count("bin"), 0u);
    }
    // Binned stepping's bin column: written as UInt8, byte for byte.
    auto bin = w.fluid.store.add(comp::bin);
    for (std::size_t i = 0; i < n; ++i) bin[i] = std::uint8_t((i * 11 + 3) % 53);
    write_vtu(file, w, {"density", "dt", "active", "bin"});
    const VtuArrays a = read_vtu(file);
    ASSERT_EQ(a.types.at("bin"), "UInt8");
    ASSERT_EQ(a.arrays.at("bin").size(), n);
    EXPECT_EQ(std::memcmp(a.arrays.at("bin").data(), bin.data(), n), 0);
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
    EXPECT_EQ(a.time, w.clock.t);
    std::filesystem::remove_all(dir);
}

// ---- BGEO and PLY: read back with readers written here from the formats' descriptions
// (partio's BGEO v5 layout, big-endian; PLY 1.0 binary_little_endian) and compared with the
// columns. Floats must come back bit-exact (dt is float32 in BGEO: compared with float(dt)).

namespace {

template <class T>
T get_be(const std::string& s, std::size_t& pos) {
    unsigned char b[sizeof(T)];
    for (std::size_t k = 0; k < sizeof(T); ++k) b[sizeof(T) - 1 - k] = static_cast<unsigned char>(s.at(pos + k));
    pos += sizeof(T);
    T v;
    std::memcpy(&v, b, sizeof(T));
    return v;
}

struct BgeoFile {
    std::int32_t points = 0;
    std::vector<std::string> names;   // point attributes after P
    std::vector<int> sizes, types;    // components, houdini type (0 float, 1 int, 5 vector)
    std::vector<std::vector<std::uint32_t>> words;  // per point: P x y z w, then the attributes
    bool closed = false;              // ends with 0x00 0xff
};

BgeoFile read_bgeo(const std::filesystem::path& file) {
    std::ifstream in(file, std::ios::binary);
    const std::string s((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    BgeoFile b;
    EXPECT_EQ(s.substr(0, 5), "BgeoV");
    std::size_t pos = 5;
    EXPECT_EQ(get_be<std::int32_t>(s, pos), 5);  // version
    b.points = get_be<std::int32_t>(s, pos);
    EXPECT_EQ(get_be<std::int32_t>(s, pos), 0);  // primitives
    EXPECT_EQ(get_be<std::int32_t>(s, pos), 0);  // point groups
    EXPECT_EQ(get_be<std::int32_t>(s, pos), 0);  // primitive groups
    const std::int32_t n_attr = get_be<std::int32_t>(s, pos);
    EXPECT_EQ(get_be<std::int32_t>(s, pos), 0);  // vertex attributes
    EXPECT_EQ(get_be<std::int32_t>(s, pos), 0);  // primitive attributes
    EXPECT_EQ(get_be<std::int32_t>(s, pos), 0);  // detail attributes
    int record = 4;
    for (int a = 0; a < n_attr; ++a) {
        const std::uint16_t len = get_be<std::uint16_t>(s, pos);
        b.names.push_back(s.substr(pos, len));
        pos += len;
        b.sizes.push_back(get_be<std::uint16_t>(s, pos));
        b.types.push_back(get_be<std::int32_t>(s, pos));
        for (int k = 0; k < b.sizes.back(); ++k) EXPECT_EQ(get_be<std::int32_t>(s, pos), 0);  // defaults
        record += b.sizes.back();
    }
    for (int i = 0; i < b.points; ++i) {
        std::vector<std::uint32_t> w;
        for (int k = 0; k < record; ++k) w.push_back(get_be<std::uint32_t>(s, pos));
        b.words.push_back(std::move(w));
    }
    b.closed = pos + 2 == s.size() && s[pos] == '\x00' && s[pos + 1] == '\xff';
    return b;
}

float as_float(std::uint32_t w) {
    float f;
    std::memcpy(&f, &w, 4);
    return f;
}

struct PlyFile {
    std::size_t vertices = 0;
    std::vector<std::pair<std::string, std::string>> props;  // (type, name)
    std::string body;
    std::size_t record = 0;
    std::map<std::string, std::size_t> offset;
};

PlyFile read_ply(const std::filesystem::path& file) {
    std::ifstream in(file, std::ios::binary);
    const std::string s((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    PlyFile p;
    const std::size_t end = s.find("end_header\n");
    std::istringstream header(s.substr(0, end));
    std::string line;
    std::getline(header, line);
    EXPECT_EQ(line, "ply");
    std::getline(header, line);
    EXPECT_EQ(line, "format binary_little_endian 1.0");
    const std::map<std::string, std::size_t> sizes{{"float", 4}, {"double", 8}, {"uchar", 1}, {"uint", 4}};
    while (std::getline(header, line)) {
        std::istringstream ls(line);
        std::string word, a, b;
        ls >> word;
        if (word == "element") {
            ls >> a >> p.vertices;
            EXPECT_EQ(a, "vertex");
        } else if (word == "property") {
            ls >> a >> b;
            p.props.emplace_back(a, b);
            p.offset[b] = p.record;
            p.record += sizes.at(a);
        }
    }
    p.body = s.substr(end + 11);
    EXPECT_EQ(p.body.size(), p.vertices * p.record) << "PLY body size";
    return p;
}

template <class T>
T ply_value(const PlyFile& p, std::size_t i, const std::string& name) {
    T v;
    std::memcpy(&v, p.body.data() + i * p.record + p.offset.at(name), sizeof(T));
    return v;
}

/// A world in individual-stepping shape with distinct values in every written column.
World filled_world() {
    Scene s = test::tank_scene(Vec3d(0.1, 0.1, 0.1), Vec3d(0.2, 0.2, 0.2));
    s.output.formats = {FrameFormat::Vtu, FrameFormat::Bgeo, FrameFormat::Ply};
    s.output.attributes = {"velocity", "density", "pressure", "dt", "active"};
    s.output.attributes_explicit = true;
    World w;
    initialise_world(w, s);
    auto rho = w.fluid.store.add(comp::density);
    auto p = w.fluid.store.add(comp::pressure);
    auto dt = w.fluid.store.add(comp::dt);
    auto active = w.fluid.store.add(comp::active);
    auto v = w.fluid.store.get(comp::velocity);
    for (std::size_t i = 0; i < rho.size(); ++i) {
        rho[i] = Real(1000 + 0.37 * double(i));
        p[i] = Real(12.5 * double(i) - 3);
        dt[i] = 1e-4 * (1.0 + double(i) / 7.0);
        active[i] = std::uint8_t(i % 3 == 0);
        v[i] = Vec3(Real(i), -Real(i) / 3, Real(0.5));
    }
    return w;
}

}  // namespace

TEST(Bgeo, ReadBackEqualsColumns) {
    World w = filled_world();
    const auto dir = std::filesystem::temp_directory_path() / "sph_io_test_bgeo";
    std::filesystem::remove_all(dir);
    write_frame(dir / "frame", w);
    for (const char* ext : {".vtu", ".bgeo", ".ply"}) EXPECT_TRUE(std::filesystem::exists(dir / (std::string("frame") + ext)));
    const BgeoFile b = read_bgeo(dir / "frame.bgeo");
    const std::size_t n = w.fluid.size();
    ASSERT_EQ(std::size_t(b.points), n);
    EXPECT_TRUE(b.closed) << "the file must end with 0x00 0xff";
    // Houdini's names and types: v is a vector, id an integer.
    EXPECT_EQ(b.names, (std::vector<std::string>{"v", "density", "pressure", "dt", "active", "id"}));
    EXPECT_EQ(b.sizes, (std::vector<int>{3, 1, 1, 1, 1, 1}));
    EXPECT_EQ(b.types, (std::vector<int>{5, 0, 0, 0, 1, 1}));
    const auto x = w.fluid.store.get(comp::position);
    const auto v = w.fluid.store.get(comp::velocity);
    const auto rho = w.fluid.store.get(comp::density);
    const auto p = w.fluid.store.get(comp::pressure);
    const auto dt = w.fluid.store.get(comp::dt);
    const auto active = w.fluid.store.get(comp::active);
    const auto id = w.fluid.store.get(comp::id);
    for (std::size_t i = 0; i < n; ++i) {
        const auto& r = b.words[i];
        for (int c = 0; c < 3; ++c) {
            ASSERT_EQ(as_float(r[std::size_t(c)]), float(x[i][c]));
            ASSERT_EQ(as_float(r[std::size_t(4 + c)]), float(v[i][c]));
        }
        ASSERT_EQ(as_float(r[3]), 1.0f);  // homogeneous w
        ASSERT_EQ(as_float(r[7]), float(rho[i]));
        ASSERT_EQ(as_float(r[8]), float(p[i]));
        ASSERT_EQ(as_float(r[9]), float(dt[i]));
        ASSERT_EQ(r[10], std::uint32_t(active[i]));
        ASSERT_EQ(r[11], id[i]);
    }
    std::filesystem::remove_all(dir);
}

TEST(Ply, ReadBackEqualsColumns) {
    World w = filled_world();
    const auto dir = std::filesystem::temp_directory_path() / "sph_io_test_ply";
    std::filesystem::remove_all(dir);
    write_ply(dir / "frame.ply", w, frame_attributes(w));
    const PlyFile f = read_ply(dir / "frame.ply");
    const std::size_t n = w.fluid.size();
    ASSERT_EQ(f.vertices, n);
    const char* real = sizeof(Real) == 4 ? "float" : "double";
    const std::vector<std::pair<std::string, std::string>> expected{
        {real, "x"},          {real, "y"},          {real, "z"},       {real, "velocity_x"},
        {real, "velocity_y"}, {real, "velocity_z"}, {real, "density"}, {real, "pressure"},
        {"double", "dt"},     {"uchar", "active"},  {"uint", "id"}};
    EXPECT_EQ(f.props, expected);
    const auto x = w.fluid.store.get(comp::position);
    const auto v = w.fluid.store.get(comp::velocity);
    const auto rho = w.fluid.store.get(comp::density);
    const auto p = w.fluid.store.get(comp::pressure);
    const auto dt = w.fluid.store.get(comp::dt);
    const auto active = w.fluid.store.get(comp::active);
    const auto id = w.fluid.store.get(comp::id);
    const char* axes[] = {"x", "y", "z"};
    for (std::size_t i = 0; i < n; ++i) {
        for (int c = 0; c < 3; ++c) {
            ASSERT_EQ(ply_value<Real>(f, i, axes[c]), x[i][c]);
            ASSERT_EQ(ply_value<Real>(f, i, std::string("velocity_") + axes[c]), v[i][c]);
        }
        ASSERT_EQ(ply_value<Real>(f, i, "density"), rho[i]);
        ASSERT_EQ(ply_value<Real>(f, i, "pressure"), p[i]);
        ASSERT_EQ(ply_value<double>(f, i, "dt"), dt[i]);
        ASSERT_EQ(ply_value<std::uint8_t>(f, i, "active"), active[i]);
        ASSERT_EQ(ply_value<std::uint32_t>(f, i, "id"), id[i]);
    }
    std::filesystem::remove_all(dir);
}

// The store's rows follow the spatial sort, so ids are out of order in any run; every format
// writes its points in id order (io.cpp, gather), each point carrying its own row's values.
// Here the id column is a seeded shuffle of 0..n-1 (with a byte column `bin` as binned stepping
// has): point k of each file must be the row whose id is k, in every array.
TEST(Frames, PointsComeInIdOrderWithTheirOwnRowsValues) {
    World w = filled_world();
    const std::size_t n = w.fluid.size();
    auto id = w.fluid.store.get(comp::id);
    std::vector<std::uint32_t> perm(n);
    for (std::size_t i = 0; i < n; ++i) perm[i] = std::uint32_t(i);
    std::mt19937 rng(5);
    std::shuffle(perm.begin(), perm.end(), rng);
    std::copy(perm.begin(), perm.end(), id.begin());
    ASSERT_FALSE(std::is_sorted(id.begin(), id.end()));
    auto bin = w.fluid.store.add(comp::bin);
    for (std::size_t i = 0; i < n; ++i) bin[i] = std::uint8_t(i % 17);
    w.scene.output.attributes.push_back("bin");
    std::vector<std::size_t> row_of(n);  // the row holding id k
    for (std::size_t i = 0; i < n; ++i) row_of[id[i]] = i;
    const auto dir = std::filesystem::temp_directory_path() / "sph_io_test_order";
    std::filesystem::remove_all(dir);
    write_frame(dir / "frame", w);
    const auto x = w.fluid.store.get(comp::position);
    const auto rho = w.fluid.store.get(comp::density);
    const auto dt = w.fluid.store.get(comp::dt);
    // VTU: every array, by its type.
    const VtuArrays a = read_vtu(dir / "frame.vtu");
    ASSERT_EQ(a.points, n);
    const Real* px = reinterpret_cast<const Real*>(a.arrays.at("position").data());
    const Real* pr = reinterpret_cast<const Real*>(a.arrays.at("density").data());
    const double* pd = reinterpret_cast<const double*>(a.arrays.at("dt").data());
    const auto* pb = reinterpret_cast<const std::uint8_t*>(a.arrays.at("bin").data());
    const auto* pi = reinterpret_cast<const std::uint32_t*>(a.arrays.at("id").data());
    for (std::size_t k = 0; k < n; ++k) {
        const std::size_t i = row_of[k];
        ASSERT_EQ(pi[k], k);
        for (int c = 0; c < 3; ++c) ASSERT_EQ(px[3 * k + c], x[i][c]) << "point " << k;
        ASSERT_EQ(pr[k], rho[i]) << "point " << k;
        ASSERT_EQ(pd[k], dt[i]) << "point " << k;
        ASSERT_EQ(pb[k], bin[i]) << "point " << k;
    }
    // PLY and BGEO: the same rows.
    const PlyFile f = read_ply(dir / "frame.ply");
    const BgeoFile b = read_bgeo(dir / "frame.bgeo");
    ASSERT_EQ(f.vertices, n);
    ASSERT_EQ(std::size_t(b.points), n);
    const auto bgeo_at = [&](const std::string& name) {  // the word index of an attribute (after P's 4)
        std::size_t w0 = 4;
        for (std::size_t k = 0; k < b.names.size(); ++k) {
            if (b.names[k] == name) return w0;
            w0 += std::size_t(b.sizes[k]);
        }
        ADD_FAILURE() << "no " << name << " in the BGEO file";
        return w0;
    };
    const std::size_t b_rho = bgeo_at("density"), b_bin = bgeo_at("bin"), b_id = bgeo_at("id");
    for (std::size_t k = 0; k < n; ++k) {
        const std::size_t i = row_of[k];
        ASSERT_EQ(ply_value<std::uint32_t>(f, k, "id"), k);
        ASSERT_EQ(ply_value<Real>(f, k, "x"), x[i].x()) << "point " << k;
        ASSERT_EQ(ply_value<Real>(f, k, "density"), rho[i]) << "point " << k;
        ASSERT_EQ(ply_value<std::uint8_t>(f, k, "bin"), bin[i]) << "point " << k;
        const auto& r = b.words[k];
        ASSERT_EQ(r[b_id], k);
        ASSERT_EQ(as_float(r[0]), float(x[i].x())) << "point " << k;
        ASSERT_EQ(as_float(r[b_rho]), float(rho[i])) << "point " << k;
        ASSERT_EQ(r[b_bin], std::uint32_t(bin[i])) << "point " << k;
    }
    std::filesystem::remove_all(dir);
}

// Outside individual stepping there are no dt/active columns: a scene that asks for them gets
// the step just taken for every particle and active = 1 (0 and 0 before the first step).
TEST(Vtu, DtAndActiveWithoutColumnsAreTheGlobalStep) {
    Scene s = test::tank_scene(Vec3d(0.1, 0.1, 0.1), Vec3d(0.2, 0.2, 0.2));
    s.output.attributes = {"dt", "active"};
    s.output.attributes_explicit = true;
    World w;
    initialise_world(w, s);
    w.clock.step = 3;
    w.step_size.set(2.5e-4);
    const auto dir = std::filesystem::temp_directory_path() / "sph_io_test_global_dt";
    std::filesystem::remove_all(dir);
    write_vtu(dir / "f.vtu", w, frame_attributes(w));
    const VtuArrays a = read_vtu(dir / "f.vtu");
    ASSERT_EQ(a.types.at("dt"), "Float64");
    const double* dt = reinterpret_cast<const double*>(a.arrays.at("dt").data());
    for (std::size_t i = 0; i < a.points; ++i) {
        ASSERT_EQ(dt[i], w.step_size.dt);
        ASSERT_EQ(a.arrays.at("active")[i], 1);
    }
    EXPECT_EQ(a.arrays.count("velocity"), 0u);  // not asked for
    std::filesystem::remove_all(dir);
}
