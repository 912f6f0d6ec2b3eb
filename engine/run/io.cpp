#include "engine/run/io.hpp"

#include "engine/data/world_init.hpp"

#include <fcntl.h>
#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>

#include <cstdio>
#include <cstring>
#include <fstream>
#include <iomanip>
#include <sstream>
#include <stdexcept>
#include <type_traits>

#include "engine/data/components.hpp"
#include "engine/data/world_init.hpp"
#include "engine/core/errors.hpp"
#include "engine/data/world.hpp"

namespace sph {

namespace {

std::string errno_text() { return std::strerror(errno); }

std::atomic<std::uint64_t> g_tmp_counter{0};

}  // namespace

std::filesystem::path temporary_name(const std::filesystem::path& target) {
    return target.parent_path() /
           (".sph.tmp" + std::to_string(::getpid()) + "." + std::to_string(g_tmp_counter++));
}

AtomicFile::AtomicFile(std::filesystem::path target) : m_target(std::move(target)) {
    if (m_target.has_parent_path()) {
        std::error_code ec;
        std::filesystem::create_directories(m_target.parent_path(), ec);
        if (ec)
            throw OutputError(m_target.parent_path().string() + ": cannot create the folder (" + ec.message() + ")");
    }
    const std::filesystem::path dir = m_target.has_parent_path() ? m_target.parent_path() : std::filesystem::path(".");
#ifdef O_TMPFILE
    m_fd = ::open(dir.c_str(), O_TMPFILE | O_WRONLY | O_CLOEXEC, 0644);
    m_unnamed = m_fd >= 0;
#endif
    if (m_fd < 0) {  // no O_TMPFILE here: a named temporary beside the target
        m_named_tmp = temporary_name(m_target);
        m_fd = ::open(m_named_tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
        if (m_fd < 0) throw OutputError(m_target.string() + ": cannot open for writing (" + errno_text() + ")");
    }
}

AtomicFile::~AtomicFile() {
    if (m_fd >= 0) ::close(m_fd);
    if (!m_named_tmp.empty()) {
        std::error_code ec;
        std::filesystem::remove(m_named_tmp, ec);
    }
}

void AtomicFile::write(std::string_view bytes) {
    const char* p = bytes.data();
    std::size_t left = bytes.size();
    while (left > 0) {
        const ssize_t n = ::write(m_fd, p, left);
        if (n < 0 && errno == EINTR) continue;
        if (n <= 0) throw OutputError(m_target.string() + ": write failed (" + errno_text() + ")");
        p += n;
        left -= std::size_t(n);
    }
}

void AtomicFile::copy_prefix(const std::filesystem::path& from, std::uint64_t bytes) {
    const int in = ::open(from.c_str(), O_RDONLY | O_CLOEXEC);
    if (in < 0) throw InputError(from.string() + ": cannot open (" + errno_text() + ")");
    std::vector<char> buf(1 << 20);
    std::uint64_t left = bytes;
    while (left > 0) {
        const ssize_t n = ::read(in, buf.data(), std::size_t(std::min<std::uint64_t>(left, buf.size())));
        if (n < 0 && errno == EINTR) continue;
        if (n <= 0) {
            ::close(in);
            throw InputError(from.string() + ": holds " + std::to_string(bytes - left) + " bytes, expected at least " +
                             std::to_string(bytes));
        }
        write(std::string_view(buf.data(), std::size_t(n)));
        left -= std::uint64_t(n);
    }
    ::close(in);
}

void AtomicFile::commit() {
    if (m_unnamed) {
        // Give the unnamed file a temporary name, then move it onto the target in one step
        // (linkat cannot replace an existing file).
        m_named_tmp = temporary_name(m_target);
        const std::string proc = "/proc/self/fd/" + std::to_string(m_fd);
        if (::linkat(AT_FDCWD, proc.c_str(), AT_FDCWD, m_named_tmp.c_str(), AT_SYMLINK_FOLLOW) != 0) {
            const std::string why = errno_text();
            m_named_tmp.clear();
            throw OutputError(m_target.string() + ": cannot link the temporary file (" + why + ")");
        }
    }
    if (::close(m_fd) != 0) {  // a full disk may only show here (delayed allocation)
        m_fd = -1;
        throw OutputError(m_target.string() + ": write failed (" + errno_text() + ")");
    }
    m_fd = -1;
    std::error_code ec;
    std::filesystem::rename(m_named_tmp, m_target, ec);
    if (ec) throw OutputError(m_target.string() + ": cannot replace it (" + ec.message() + ")");
    m_named_tmp.clear();
}

void write_file_atomic(const std::filesystem::path& file, std::string_view content) {
    AtomicFile f(file);
    f.write(content);
    f.commit();
}

namespace {

/// One point attribute of a frame, gathered once and written by every format.
struct FrameArray {
    std::string name;
    enum Type { F32, F64, U8, U32 } type;
    int components;
    std::string bytes;  ///< n * components values, native (little-endian) order

    std::size_t value_size() const { return type == F64 ? 8 : type == U8 ? 1 : 4; }
};

template <class T>
constexpr FrameArray::Type array_type() {
    if constexpr (std::is_same_v<T, float>) return FrameArray::F32;
    else if constexpr (std::is_same_v<T, double>) return FrameArray::F64;
    else if constexpr (std::is_same_v<T, std::uint8_t>) return FrameArray::U8;
    else if constexpr (std::is_same_v<T, std::uint32_t>) return FrameArray::U32;
    else static_assert(sizeof(T) == 0, "no frame type for this column type");
}

template <class T>
FrameArray make_array(std::string name, const T* data, std::size_t values, int components) {
    FrameArray a{std::move(name), array_type<T>(), components, std::string(sizeof(T) * values, '\0')};
    if (values) std::memcpy(a.bytes.data(), data, a.bytes.size());
    return a;
}

FrameArray vec3_array(const std::string& name, std::span<const Vec3> v) {
    std::vector<Real> flat(3 * v.size());
    for (std::size_t i = 0; i < v.size(); ++i)
        for (int c = 0; c < 3; ++c) flat[3 * i + c] = v[i][c];
    return make_array(name, flat.data(), flat.size(), 3);
}

/// The frame's arrays: position first, then the attributes in the order asked, then id.
/// `dt` and `active` exist as columns only in individual and binned stepping; in the other modes
/// every particle took the step just taken (0 before the first step) and was evaluated in it.
/// `bin` (binned stepping's bin of each particle) is written only where it exists.
std::vector<FrameArray> gather(const World& world, const std::vector<std::string>& attributes) {
    const auto& store = world.fluid.store;
    const std::size_t n = store.size();
    std::vector<FrameArray> out;
    out.push_back(vec3_array("position", store.get(comp::position)));
    for (const auto& a : attributes) {
        if (a == "position" || a == "id") continue;  // always written
        if (a == "dt") {
            if (store.has(comp::dt.name)) {
                const auto v = store.get(comp::dt);
                out.push_back(make_array(a, v.data(), n, 1));
            } else {
                const std::vector<double> v(n, world.clock.step > 0 ? world.step_size.dt : 0.0);
                out.push_back(make_array(a, v.data(), n, 1));
            }
        } else if (a == "active") {
            if (store.has(comp::active.name)) {
                const auto v = store.get(comp::active);
                out.push_back(make_array(a, v.data(), n, 1));
            } else {
                const std::vector<std::uint8_t> v(n, world.clock.step > 0 ? 1 : 0);
                out.push_back(make_array(a, v.data(), n, 1));
            }
        } else if (a == "bin") {
            if (!store.has(comp::bin.name)) continue;  // binned stepping only
            const auto v = store.get(comp::bin);
            out.push_back(make_array(a, v.data(), n, 1));
        } else if (!store.has(a)) {
            continue;  // e.g. acceleration in a recipe that never stores it
        } else if (store.type_of(a) == typeid(Vec3)) {
            out.push_back(vec3_array(a, store.get(Component<Vec3>{a})));
        } else {
            const auto v = store.get(Component<Real>{a});
            out.push_back(make_array(a, v.data(), n, 1));
        }
    }
    if (store.has(comp::id.name)) {
        const auto v = store.get(comp::id);
        out.push_back(make_array("id", v.data(), n, 1));
        // Points in id order: the store's rows follow the spatial sort, which reorders almost
        // every row between frames; programs that match points by index across frames (Blender's
        // point caches, a ParaView temporal filter) then see the same particle at the same index.
        if (!std::is_sorted(v.begin(), v.end())) {
            std::vector<std::uint32_t> order(n);
            for (std::size_t i = 0; i < n; ++i) order[i] = std::uint32_t(i);
            std::sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) { return v[a] < v[b]; });
            for (FrameArray& a : out) {
                const std::size_t bytes = a.value_size() * std::size_t(a.components);
                std::string sorted(a.bytes.size(), '\0');
                for (std::size_t k = 0; k < n; ++k)
                    std::memcpy(sorted.data() + k * bytes, a.bytes.data() + std::size_t(order[k]) * bytes, bytes);
                a.bytes = std::move(sorted);
            }
        }
    }
    return out;
}

const char* vtk_type(FrameArray::Type t) {
    switch (t) {
        case FrameArray::F32: return "Float32";
        case FrameArray::F64: return "Float64";
        case FrameArray::U8: return "UInt8";
        case FrameArray::U32: return "UInt32";
    }
    return "";
}

/// Appends one value in big-endian order (BGEO is big-endian throughout).
template <class T>
void put_be(std::string& out, T value) {
    static_assert(sizeof(T) == 2 || sizeof(T) == 4);
    unsigned char b[sizeof(T)];
    std::memcpy(b, &value, sizeof(T));
    for (std::size_t k = sizeof(T); k-- > 0;) out.push_back(char(b[k]));
}

/// One value of an array as a 32-bit BGEO word: floats as float32, integers as int32.
std::uint32_t bgeo_word(const FrameArray& a, std::size_t index) {
    const char* p = a.bytes.data() + index * a.value_size();
    std::uint32_t w = 0;
    switch (a.type) {
        case FrameArray::F32: std::memcpy(&w, p, 4); break;
        case FrameArray::F64: {
            double d;
            std::memcpy(&d, p, 8);
            const float f = float(d);
            std::memcpy(&w, &f, 4);
            break;
        }
        case FrameArray::U8: w = std::uint8_t(*p); break;
        case FrameArray::U32: std::memcpy(&w, p, 4); break;
    }
    return w;
}

const char* ply_type(FrameArray::Type t) {
    switch (t) {
        case FrameArray::F32: return "float";
        case FrameArray::F64: return "double";
        case FrameArray::U8: return "uchar";
        case FrameArray::U32: return "uint";
    }
    return "";
}

}  // namespace

std::vector<std::string> frame_attributes(const World& world) {
    const OutputParams& o = world.scene.output;
    std::vector<std::string> a = o.attributes;
    if (!o.attributes_explicit) {
        // Default list: per-particle stepping also shows each particle's step and activity
        // (and, binned, its bin).
        if (world.fluid.store.has(comp::dt.name)) a.emplace_back("dt");
        if (world.fluid.store.has(comp::active.name)) a.emplace_back("active");
        if (world.fluid.store.has(comp::bin.name)) a.emplace_back("bin");
    }
    return a;
}

namespace {

std::size_t point_count(const std::vector<FrameArray>& arrays) {
    return arrays.empty() ? 0 : arrays[0].bytes.size() / (arrays[0].value_size() * 3);
}

/// The .vtu bytes of `arrays` (arrays[0] the positions) at simulated time t.
std::string vtu_text(const std::vector<FrameArray>& arrays, double t) {
    const std::size_t n = point_count(arrays);
    std::vector<std::int64_t> conn(n), offs(n);
    std::vector<std::uint8_t> types(n, 1);  // VTK_VERTEX
    for (std::size_t i = 0; i < n; ++i) {
        conn[i] = std::int64_t(i);
        offs[i] = std::int64_t(i + 1);
    }

    // Appended raw data: each array's bytes are preceded by their byte count as one integer of
    // the file's header_type (UInt64 here); `offset` counts from the byte after the '_'.
    std::ostringstream xml;
    std::string appended;
    std::uint64_t offset = 0;
    auto emit = [&](const char* type, const std::string& name, int components, const std::string& bytes) {
        xml << "        <DataArray type=\"" << type << "\" Name=\"" << name << "\"";
        if (components != 1) xml << " NumberOfComponents=\"" << components << "\"";
        xml << " format=\"appended\" offset=\"" << offset << "\"/>\n";
        const std::uint64_t len = bytes.size();
        appended.append(reinterpret_cast<const char*>(&len), sizeof(len));
        appended += bytes;
        offset += sizeof(len) + len;
    };
    auto raw = [](const auto& v) {
        return std::string(reinterpret_cast<const char*>(v.data()), v.size() * sizeof(v[0]));
    };
    xml << "<?xml version=\"1.0\"?>\n"
        << "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n"
        << "  <UnstructuredGrid>\n"
        // Full precision, so a frame's time matches the end of a stats.csv step exactly.
        << "    <FieldData>\n      <DataArray type=\"Float64\" Name=\"TimeValue\" NumberOfTuples=\"1\" format=\"ascii\">"
        << std::setprecision(17) << t << "</DataArray>\n    </FieldData>\n"
        << "    <Piece NumberOfPoints=\"" << n << "\" NumberOfCells=\"" << n << "\">\n";
    xml << "      <PointData>\n";
    for (std::size_t k = 1; k < arrays.size(); ++k)
        emit(vtk_type(arrays[k].type), arrays[k].name, arrays[k].components, arrays[k].bytes);
    xml << "      </PointData>\n      <Points>\n";
    emit(vtk_type(arrays[0].type), "position", 3, arrays[0].bytes);
    xml << "      </Points>\n      <Cells>\n";
    emit("Int64", "connectivity", 1, raw(conn));
    emit("Int64", "offsets", 1, raw(offs));
    emit("UInt8", "types", 1, raw(types));
    xml << "      </Cells>\n    </Piece>\n  </UnstructuredGrid>\n  <AppendedData encoding=\"raw\">\n   _";
    std::string out = xml.str();
    out += appended;
    out += "\n  </AppendedData>\n</VTKFile>\n";
    return out;
}

/// The .bgeo bytes of `arrays` (arrays[0] the positions).
std::string bgeo_text(const std::vector<FrameArray>& arrays) {
    // Houdini's classic binary geometry, version 5, as partio reads and writes it
    // (partio src/lib/io/BGEO.cpp): a big-endian header, the point attribute dictionary, then
    // per point P as x y z w (w = 1) and each attribute's 32-bit words, no primitives, no
    // detail attributes, and the two closing bytes 0x00 0xff. Houdini's names are used:
    // "v" for velocity, "accel" for acceleration. Floats are float32 and integers int32 (the
    // format has no 64-bit type), so dt is rounded to float here.
    const std::size_t n = point_count(arrays);
    std::string out;
    out.append("Bgeo", 4);
    out.push_back('V');
    const std::int32_t header[] = {5, std::int32_t(n), 0, 0, 0, std::int32_t(arrays.size() - 1), 0, 0, 0};
    for (const std::int32_t v : header) put_be(out, v);
    for (std::size_t k = 1; k < arrays.size(); ++k) {
        const FrameArray& a = arrays[k];
        const std::string name = a.name == "velocity" ? "v" : a.name == "acceleration" ? "accel" : a.name;
        put_be(out, std::uint16_t(name.size()));
        out += name;
        const bool is_float = a.type == FrameArray::F32 || a.type == FrameArray::F64;
        put_be(out, std::uint16_t(a.components));
        put_be(out, std::int32_t(a.components == 3 && is_float ? 5 : is_float ? 0 : 1));  // vector, float, int
        for (int c = 0; c < a.components; ++c) put_be(out, std::int32_t(0));              // defaults
    }
    out.reserve(out.size() + n * 4 * (4 + 3 * arrays.size()));
    for (std::size_t i = 0; i < n; ++i) {
        for (int c = 0; c < 3; ++c) put_be(out, bgeo_word(arrays[0], 3 * i + std::size_t(c)));
        const float w = 1.0f;
        std::uint32_t ww;
        std::memcpy(&ww, &w, 4);
        put_be(out, ww);
        for (std::size_t k = 1; k < arrays.size(); ++k)
            for (int c = 0; c < arrays[k].components; ++c)
                put_be(out, bgeo_word(arrays[k], i * std::size_t(arrays[k].components) + std::size_t(c)));
    }
    out.push_back('\x00');
    out.push_back('\xff');
    return out;
}

/// The .ply bytes of `arrays` (arrays[0] the positions) at simulated time t.
std::string ply_text(const std::vector<FrameArray>& arrays, double t) {
    // PLY 1.0, binary little-endian (Turk's format as Blender imports it): one `vertex`
    // element, x y z then one property per attribute component, named <attr> for scalars and
    // <attr>_x/_y/_z for vectors; types as stored (dt as double, active as uchar, id as uint).
    const std::size_t n = point_count(arrays);
    std::ostringstream h;
    h << "ply\nformat binary_little_endian 1.0\ncomment sph frame, t = " << std::setprecision(17) << t
      << " s\nelement vertex " << n << "\n";
    const char* axes[] = {"x", "y", "z"};
    for (int c = 0; c < 3; ++c) h << "property " << ply_type(arrays[0].type) << ' ' << axes[c] << "\n";
    for (std::size_t k = 1; k < arrays.size(); ++k) {
        if (arrays[k].components == 1)
            h << "property " << ply_type(arrays[k].type) << ' ' << arrays[k].name << "\n";
        else
            for (int c = 0; c < arrays[k].components; ++c)
                h << "property " << ply_type(arrays[k].type) << ' ' << arrays[k].name << '_' << axes[c] << "\n";
    }
    h << "end_header\n";
    std::string out = h.str();
    std::size_t record = 0;
    for (const auto& a : arrays) record += a.value_size() * std::size_t(a.components);
    out.reserve(out.size() + n * record);
    for (std::size_t i = 0; i < n; ++i)
        for (const auto& a : arrays) {
            const std::size_t bytes = a.value_size() * std::size_t(a.components);
            out.append(a.bytes.data() + i * bytes, bytes);
        }
    return out;
}

void write_arrays(const std::filesystem::path& stem, const std::vector<FrameArray>& arrays,
                  const std::vector<FrameFormat>& formats, double t) {
    for (const FrameFormat f : formats) {
        switch (f) {
            case FrameFormat::Vtu: write_file_atomic(stem.string() + ".vtu", vtu_text(arrays, t)); break;
            case FrameFormat::Bgeo: write_file_atomic(stem.string() + ".bgeo", bgeo_text(arrays)); break;
            case FrameFormat::Ply: write_file_atomic(stem.string() + ".ply", ply_text(arrays, t)); break;
            case FrameFormat::Vdb:
            case FrameFormat::Mesh: break;  // the surface formats: the recorder builds them (surface.hpp)
        }
    }
}

}  // namespace

void write_vtu(const std::filesystem::path& file, const World& world, const std::vector<std::string>& attributes) {
    write_file_atomic(file, vtu_text(gather(world, attributes), world.clock.t));
}

void write_bgeo(const std::filesystem::path& file, const World& world, const std::vector<std::string>& attributes) {
    write_file_atomic(file, bgeo_text(gather(world, attributes)));
}

void write_ply(const std::filesystem::path& file, const World& world, const std::vector<std::string>& attributes) {
    write_file_atomic(file, ply_text(gather(world, attributes), world.clock.t));
}

void write_boundary(const std::filesystem::path& stem, const World& world, std::size_t begin, std::size_t end,
                    double t) {
    const auto& store = world.boundary.store;
    end = std::min(end, store.size());
    begin = std::min(begin, end);
    const auto rows = [&](std::span<const Vec3> v) { return v.subspan(begin, end - begin); };
    std::vector<FrameArray> arrays;
    arrays.push_back(vec3_array("position", rows(store.get(comp::position))));
    // Methods that read normals keep them in the store; for the others they are sampled again.
    if (store.has(comp::normal.name))
        arrays.push_back(vec3_array("normal", rows(store.get(comp::normal))));
    else
        arrays.push_back(vec3_array("normal", sampled_boundary_normals(world, begin, end)));
    if (store.has(comp::velocity.name)) arrays.push_back(vec3_array("velocity", rows(store.get(comp::velocity))));
    std::vector<std::uint32_t> index(end - begin);
    for (std::size_t i = 0; i < index.size(); ++i) index[i] = std::uint32_t(begin + i);
    arrays.push_back(make_array("id", index.data(), index.size(), 1));
    // In the scene's particle formats; as .ply when it asks for surfaces only.
    std::vector<FrameFormat> formats;
    for (const FrameFormat f : world.scene.output.formats)
        if (is_particle_format(f)) formats.push_back(f);
    if (formats.empty()) formats.push_back(FrameFormat::Ply);
    write_arrays(stem, arrays, formats, t);
}

void write_frame(const std::filesystem::path& stem, const World& world) {
    write_arrays(stem, gather(world, frame_attributes(world)), world.scene.output.formats, world.clock.t);
}

std::size_t peak_memory_bytes() {
    rusage u{};
    getrusage(RUSAGE_SELF, &u);
    return std::size_t(u.ru_maxrss) * 1024;
}

}  // namespace sph
