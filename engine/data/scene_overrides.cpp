/// @file
/// @brief Scene loading, part 2: command-line overrides (--set path=value) applied to the document.
#include "engine/data/scene_detail.hpp"



#include <Eigen/Geometry>

#include <unistd.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cerrno>
#include <climits>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <memory>
#include <numbers>
#include <span>
#include <string_view>
#include <system_error>
#include <utility>

#include "engine/core/errors.hpp"

namespace sph {

using namespace scene_detail;

namespace scene_detail {

// ---- Command-line overrides. ----

/// Splits a JSON pointer into unescaped tokens; throws InputError for "~" not followed by 0/1.
std::vector<std::string> pointer_tokens(const std::string& pointer, const std::string& file) {
    std::vector<std::string> tokens;
    if (pointer.empty()) return tokens;
    if (pointer[0] != '/') {
        throw InputError(file + ": cannot apply override " + in_quotes(pointer) +
                         ": expected a JSON pointer starting with '/'");
    }
    std::string token;
    for (std::size_t i = 1; i <= pointer.size(); ++i) {
        if (i == pointer.size() || pointer[i] == '/') {
            tokens.push_back(token);
            token.clear();
        } else if (pointer[i] == '~') {
            if (i + 1 < pointer.size() && (pointer[i + 1] == '0' || pointer[i + 1] == '1')) {
                token += pointer[i + 1] == '0' ? '~' : '/';
                ++i;
            } else {
                throw InputError(file + ": cannot apply override " + in_quotes(pointer) +
                                 ": '~' must be followed by 0 or 1 in a JSON pointer");
            }
        } else {
            token += pointer[i];
        }
    }
    return tokens;
}

/// Sets `value` at `tokens` in `doc`, creating objects on the way; returns the canonical path.
std::string apply_override(json& doc, const std::vector<std::string>& tokens, const json& value,
                           const std::string& file) {
    json* cur = &doc;
    std::string path;
    for (const std::string& t : tokens) {
        if (cur->is_null()) *cur = json::object();
        if (cur->is_object()) {
            cur = &(*cur)[t];
            path = child(path, t);
        } else if (cur->is_array()) {
            const bool digits = !t.empty() && std::all_of(t.begin(), t.end(), [](char c) {
                return std::isdigit(static_cast<unsigned char>(c));
            }) && (t.size() == 1 || t[0] != '0');
            const std::size_t index = digits && t.size() < 10 ? std::stoul(t) : SIZE_MAX;
            if (index >= cur->size()) {
                throw SceneError(file, child(path, t), "nothing",
                                 cur->empty() ? std::string("an element, but the array is empty "
                                                            "(set on the command line)")
                                              : "an array index from 0 to " +
                                                    std::to_string(cur->size() - 1) +
                                                    " (set on the command line)");
            }
            cur = &(*cur)[index];
            path = child(path, index);
        } else {
            throw SceneError(file, shown(path), dump(*cur),
                             "an object holding " + in_quotes(t) + " (set on the command line)");
        }
    }
    *cur = value;
    return path;
}


}  // namespace scene_detail

std::pair<std::string, nlohmann::json> parse_override(const std::string& assignment) {
    const auto trim = [](std::string s) {
        const auto first = s.find_first_not_of(" \t");
        if (first == std::string::npos) return std::string();
        return s.substr(first, s.find_last_not_of(" \t") - first + 1);
    };
    const std::string usage = "--set " + in_quotes(assignment) + ": expected path=value, e.g. " +
                              "simulation.stepping.mode=global";
    const auto eq = assignment.find('=');
    if (eq == std::string::npos) throw InputError(usage);
    const std::string lhs = trim(assignment.substr(0, eq));
    const std::string rhs = trim(assignment.substr(eq + 1));
    if (lhs.empty()) throw InputError(usage + " (the path is empty)");

    std::string pointer;
    if (lhs[0] == '/') {
        pointer = lhs;  // already a JSON pointer
    } else {
        std::size_t start = 0;
        while (true) {
            const auto dot = lhs.find('.', start);
            const std::string key =
                lhs.substr(start, dot == std::string::npos ? std::string::npos : dot - start);
            if (key.empty()) throw InputError(usage + " (empty key in the path)");
            pointer += '/';
            pointer += escape_token(key);
            if (dot == std::string::npos) break;
            start = dot + 1;
        }
    }

    json value;
    try {
        value = json::parse(rhs, nullptr, /*allow_exceptions=*/true, /*ignore_comments=*/false);
    } catch (const json::parse_error&) {
        value = rhs;  // a bare word: `mode=global`
    } catch (const json::out_of_range&) {
        throw InputError("--set " + in_quotes(assignment) + ": the number overflows a double");
    }
    return {pointer, value};
}

void read_obj(const std::filesystem::path& file, std::vector<Vec3d>& vertices, std::vector<std::array<int, 3>>& triangles,
              const std::string& name) {
    const std::string shown = name.empty() ? file.string() : name;
    std::FILE* f = std::fopen(file.string().c_str(), "rb");
    if (!f) throw InputError(shown + ": cannot open OBJ file");
    std::string text;
    std::array<char, 1 << 16> buf{};
    std::size_t got = 0;
    while ((got = std::fread(buf.data(), 1, buf.size(), f)) > 0) text.append(buf.data(), got);
    std::fclose(f);
    vertices.clear();
    triangles.clear();
    std::size_t line_no = 0, pos = 0;
    while (pos < text.size()) {
        std::size_t end = text.find('\n', pos);
        if (end == std::string::npos) end = text.size();
        std::string line = text.substr(pos, end - pos);
        pos = end + 1;
        ++line_no;
        if (!line.empty() && line.back() == '\r') line.pop_back();
        const auto bad = [&](const std::string& why) {
            return InputError(shown + ":" + std::to_string(line_no) + ": " + why + " in \"" + truncate(line, 60) + "\"");
        };
        std::size_t p = line.find_first_not_of(" \t");
        if (p == std::string::npos || line[p] == '#') continue;
        const std::size_t q = line.find_first_of(" \t", p);
        const std::string word = line.substr(p, q == std::string::npos ? std::string::npos : q - p);
        std::vector<std::string> args;
        for (std::size_t a = q; a != std::string::npos && a < line.size();) {
            const std::size_t b0 = line.find_first_not_of(" \t", a);
            if (b0 == std::string::npos) break;
            const std::size_t b1 = line.find_first_of(" \t", b0);
            args.push_back(line.substr(b0, b1 == std::string::npos ? std::string::npos : b1 - b0));
            a = b1;
        }
        if (word == "v") {
            if (args.size() < 3) throw bad("a vertex needs 3 coordinates");
            Vec3d v;
            for (int c = 0; c < 3; ++c) {
                char* e = nullptr;
                v[c] = std::strtod(args[c].c_str(), &e);
                if (e == args[c].c_str() || *e != '\0' || !std::isfinite(v[c])) throw bad("invalid number \"" + args[c] + "\"");
            }
            vertices.push_back(v);
        } else if (word == "f") {
            if (args.size() < 3) throw bad("a face needs at least 3 vertices");
            std::vector<int> idx;
            for (const auto& a : args) {
                const std::string first = a.substr(0, a.find('/'));
                char* e = nullptr;
                const long k = std::strtol(first.c_str(), &e, 10);
                if (e == first.c_str() || *e != '\0' || k == 0) throw bad("invalid vertex reference \"" + a + "\"");
                const long resolved = k > 0 ? k - 1 : long(vertices.size()) + k;  // negative: relative
                if (resolved < 0 || resolved >= long(vertices.size()))
                    throw bad("vertex " + std::to_string(k) + " is not defined before this face (" +
                              std::to_string(vertices.size()) + " so far)");
                idx.push_back(int(resolved));
            }
            for (std::size_t t = 1; t + 1 < idx.size(); ++t) triangles.push_back({idx[0], idx[t], idx[t + 1]});
        }
    }
}


}  // namespace sph
