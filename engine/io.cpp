#include "engine/io.hpp"

#include <sys/resource.h>
#include <unistd.h>

#include <cstdio>
#include <cstring>
#include <fstream>
#include <sstream>
#include <stdexcept>

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

constexpr const char* real_type() { return sizeof(Real) == 4 ? "Float32" : "Float64"; }

struct Blob {
    std::string header;  // DataArray XML
    std::string bytes;   // raw payload
};

template <class T>
std::string raw_bytes(const T* data, std::size_t count) {
    std::string s(sizeof(T) * count, '\0');
    if (count) std::memcpy(s.data(), data, s.size());
    return s;
}

}  // namespace

void write_vtu(const std::filesystem::path& file, const World& world,
               const std::vector<std::string>& attributes) {
    const auto& store = world.fluid.store;
    const std::size_t n = store.size();
    std::vector<Blob> point_data;
    auto vec3_blob = [&](const std::string& name, std::span<const Vec3> v) {
        std::vector<Real> flat(3 * n);
        for (std::size_t i = 0; i < n; ++i)
            for (int a = 0; a < 3; ++a) flat[3 * i + a] = v[i][a];
        return Blob{"<DataArray type=\"" + std::string(real_type()) + "\" Name=\"" + name +
                        "\" NumberOfComponents=\"3\" format=\"appended\" offset=\"",
                    raw_bytes(flat.data(), flat.size())};
    };
    auto scalar_blob = [&](const std::string& name, std::span<const Real> v) {
        return Blob{"<DataArray type=\"" + std::string(real_type()) + "\" Name=\"" + name +
                        "\" format=\"appended\" offset=\"",
                    raw_bytes(v.data(), v.size())};
    };
    for (const auto& a : attributes) {
        if (!store.has(a)) continue;  // e.g. acceleration in a recipe that never stores it
        if (a == "velocity" || a == "acceleration")
            point_data.push_back(vec3_blob(a, store.get(Component<Vec3>{a})));
        else
            point_data.push_back(scalar_blob(a, store.get(Component<Real>{a})));
    }
    if (store.has(comp::id.name)) {
        auto ids = store.get(comp::id);
        point_data.push_back(Blob{"<DataArray type=\"UInt32\" Name=\"id\" format=\"appended\" offset=\"",
                                  raw_bytes(ids.data(), ids.size())});
    }
    Blob points = vec3_blob("position", store.get(comp::position));
    std::vector<std::int64_t> conn(n), offs(n);
    std::vector<std::uint8_t> types(n, 1);  // VTK_VERTEX
    for (std::size_t i = 0; i < n; ++i) {
        conn[i] = std::int64_t(i);
        offs[i] = std::int64_t(i + 1);
    }
    Blob c_conn{"<DataArray type=\"Int64\" Name=\"connectivity\" format=\"appended\" offset=\"",
                raw_bytes(conn.data(), n)};
    Blob c_offs{"<DataArray type=\"Int64\" Name=\"offsets\" format=\"appended\" offset=\"", raw_bytes(offs.data(), n)};
    Blob c_types{"<DataArray type=\"UInt8\" Name=\"types\" format=\"appended\" offset=\"", raw_bytes(types.data(), n)};

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
        << "    <FieldData>\n      <DataArray type=\"Float64\" Name=\"TimeValue\" NumberOfTuples=\"1\" format=\"ascii\">"
        << world.step.t << "</DataArray>\n    </FieldData>\n"
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
