#include "engine/io.hpp"

#include <sys/resource.h>
#include <unistd.h>

#include <cstdio>
#include <cstring>
#include <fstream>
#include <iomanip>
#include <sstream>
#include <stdexcept>
#include <type_traits>

#include "engine/components.hpp"
#include "engine/errors.hpp"
#include "engine/world.hpp"

namespace sph {

void write_file_atomic(const std::filesystem::path& file, std::string_view content) {
    if (file.has_parent_path()) std::filesystem::create_directories(file.parent_path());
    const std::filesystem::path tmp = file.string() + ".tmp" + std::to_string(::getpid());
    {
        std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
        if (!out) throw InputError(file.string() + ": cannot open for writing (" + std::strerror(errno) + ")");
        out.write(content.data(), std::streamsize(content.size()));
        out.flush();
        if (!out) {
            std::filesystem::remove(tmp);
            throw std::runtime_error(file.string() + ": write failed (" + std::strerror(errno) + ")");
        }
    }
    std::filesystem::rename(tmp, file);
}

namespace {

/// VTK XML type names of the column types we write (VTK file formats, "DataArray" type).
template <class T>
constexpr const char* vtk_type() {
    if constexpr (std::is_same_v<T, float>) return "Float32";
    else if constexpr (std::is_same_v<T, double>) return "Float64";
    else if constexpr (std::is_same_v<T, std::uint8_t>) return "UInt8";
    else if constexpr (std::is_same_v<T, std::uint32_t>) return "UInt32";
    else if constexpr (std::is_same_v<T, std::int64_t>) return "Int64";
    else static_assert(sizeof(T) == 0, "no VTK type for this column type");
}

/// One appended DataArray: the XML element up to its offset attribute, and the raw payload.
struct Blob {
    std::string header;
    std::string bytes;
};

template <class T>
Blob array_blob(const std::string& name, const T* data, std::size_t count, int components = 1) {
    std::string header = "<DataArray type=\"" + std::string(vtk_type<T>()) + "\" Name=\"" + name + "\"";
    if (components != 1) header += " NumberOfComponents=\"" + std::to_string(components) + "\"";
    header += " format=\"appended\" offset=\"";
    std::string bytes(sizeof(T) * count, '\0');
    if (count) std::memcpy(bytes.data(), data, bytes.size());
    return Blob{std::move(header), std::move(bytes)};
}

template <class T>
Blob column_blob(const ComponentStore& store, Component<T> c) {
    const auto v = store.get(c);
    return array_blob(std::string(c.name), v.data(), v.size());
}

Blob vec3_blob(const std::string& name, std::span<const Vec3> v) {
    std::vector<Real> flat(3 * v.size());
    for (std::size_t i = 0; i < v.size(); ++i)
        for (int a = 0; a < 3; ++a) flat[3 * i + a] = v[i][a];
    return array_blob(name, flat.data(), flat.size(), 3);
}

}  // namespace

void write_vtu(const std::filesystem::path& file, const World& world,
               const std::vector<std::string>& attributes) {
    const auto& store = world.fluid.store;
    const std::size_t n = store.size();
    std::vector<Blob> point_data;
    for (const auto& a : attributes) {
        if (!store.has(a)) continue;  // e.g. acceleration in a recipe that never stores it
        if (a == "velocity" || a == "acceleration")
            point_data.push_back(vec3_blob(a, store.get(Component<Vec3>{a})));
        else
            point_data.push_back(column_blob(store, Component<Real>{a}));
    }
    // Individual stepping (the only mode that registers these columns): each particle's step
    // Delta t_i (s, double as stored) and whether it was evaluated in the step just taken. In
    // the other modes every particle shares the step in stats.csv, so nothing is added.
    if (store.has(comp::dt.name)) point_data.push_back(column_blob(store, comp::dt));
    if (store.has(comp::active.name)) point_data.push_back(column_blob(store, comp::active));
    if (store.has(comp::id.name)) point_data.push_back(column_blob(store, comp::id));
    Blob points = vec3_blob("position", store.get(comp::position));
    std::vector<std::int64_t> conn(n), offs(n);
    std::vector<std::uint8_t> types(n, 1);  // VTK_VERTEX
    for (std::size_t i = 0; i < n; ++i) {
        conn[i] = std::int64_t(i);
        offs[i] = std::int64_t(i + 1);
    }
    const Blob c_conn = array_blob("connectivity", conn.data(), n);
    const Blob c_offs = array_blob("offsets", offs.data(), n);
    const Blob c_types = array_blob("types", types.data(), n);

    // Appended raw data: each array's bytes are preceded by their byte count as one integer of
    // the file's header_type (UInt64 here); `offset` counts from the byte after the '_'.
    std::ostringstream xml;
    std::string appended;
    std::uint64_t offset = 0;
    auto emit = [&](const Blob& b) {
        xml << "        " << b.header << offset << "\"/>\n";
        const std::uint64_t len = b.bytes.size();
        appended.append(reinterpret_cast<const char*>(&len), sizeof(len));
        appended += b.bytes;
        offset += sizeof(len) + len;
    };
    xml << "<?xml version=\"1.0\"?>\n"
        << "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n"
        << "  <UnstructuredGrid>\n"
        // Full precision, so a frame's time matches the end of a stats.csv step exactly.
        << "    <FieldData>\n      <DataArray type=\"Float64\" Name=\"TimeValue\" NumberOfTuples=\"1\" format=\"ascii\">"
        << std::setprecision(17) << world.step.t << "</DataArray>\n    </FieldData>\n"
        << "    <Piece NumberOfPoints=\"" << n << "\" NumberOfCells=\"" << n << "\">\n";
    xml << "      <PointData>\n";
    for (const auto& b : point_data) emit(b);
    xml << "      </PointData>\n      <Points>\n";
    emit(points);
    xml << "      </Points>\n      <Cells>\n";
    emit(c_conn);
    emit(c_offs);
    emit(c_types);
    xml << "      </Cells>\n    </Piece>\n  </UnstructuredGrid>\n  <AppendedData encoding=\"raw\">\n   _";
    std::string out = xml.str();
    out += appended;
    out += "\n  </AppendedData>\n</VTKFile>\n";
    write_file_atomic(file, out);
}

std::size_t peak_memory_bytes() {
    rusage u{};
    getrusage(RUSAGE_SELF, &u);
    return std::size_t(u.ru_maxrss) * 1024;
}

}  // namespace sph
