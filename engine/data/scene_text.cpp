/// @file
/// @brief Scene loading, part 1: the string helpers of its messages and JSON text -> document, with positions and paths for every kind of failure.
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

namespace sph::scene_detail {

// ---- Small string helpers. ----

/// JSON pointer token escaping (RFC 6901): '~' -> "~0", '/' -> "~1".
std::string escape_token(std::string_view key) {
    std::string out;
    for (const char c : key) {
        if (c == '~') {
            out += "~0";
        } else if (c == '/') {
            out += "~1";
        } else {
            out += c;
        }
    }
    return out;
}

// Paths are JSON pointers; the root is "" internally and shown as "/".
std::string child(const std::string& path, std::string_view key) {
    return path + "/" + escape_token(key);
}
std::string child(const std::string& path, std::size_t index) {
    return path + "/" + std::to_string(index);
}
std::string shown(const std::string& path) {
    return path.empty() ? "/" : path;
}

/// Keeps messages one readable line: long values are cut (on a UTF-8 boundary) with "...".
std::string truncate(std::string s, std::size_t max_chars) {
    if (s.size() <= max_chars) return s;
    std::size_t cut = max_chars - 3;
    while (cut > 0 && (static_cast<unsigned char>(s[cut]) & 0xC0) == 0x80) --cut;
    s.resize(cut);
    return s + "...";
}

std::string dump(const json& v) {
    return truncate(v.dump());
}
std::string in_quotes(std::string_view s) {
    return json(std::string(s)).dump();
}

/// Shortest round-trip form ("0.1", "1e-05"), without the ".0" json adds to integral values.
std::string fmt_num(double x) {
    std::string s = json(x).dump();
    if (s.size() > 2 && s.ends_with(".0")) s.resize(s.size() - 2);
    return s;
}

/// Computed values (spacing, ...): 6 significant digits, so 0.04000000000000001 reads 0.04.
std::string fmt_computed(double x) {
    std::array<char, 64> buf{};
    std::snprintf(buf.data(), buf.size(), "%.6g", x);
    return buf.data();
}

std::string fmt_vec(const Vec3d& v) {
    return "[" + fmt_num(v[0]) + "," + fmt_num(v[1]) + "," + fmt_num(v[2]) + "]";
}
std::string fmt_vec_computed(const Vec3d& v) {
    return "[" + fmt_computed(v[0]) + "," + fmt_computed(v[1]) + "," + fmt_computed(v[2]) + "]";
}

/// Plain digits up to 1e15 ("125000000000000"), then 3 significant digits; never "inf".
std::string fmt_large(double x, int decimals) {
    if (!std::isfinite(x)) return "more than 1e308";
    std::array<char, 64> buf{};
    if (x < 1e15) {
        std::snprintf(buf.data(), buf.size(), "%.*f", decimals, x);
    } else {
        std::snprintf(buf.data(), buf.size(), "%.3g", x);
    }
    return buf.data();
}

std::string join(std::span<const char* const> names, bool quote) {
    std::string out;
    for (std::size_t i = 0; i < names.size(); ++i) {
        if (i > 0) out += ", ";
        out += quote ? in_quotes(names[i]) : std::string(names[i]);
    }
    return out;
}

std::string lower(std::string_view s) {
    std::string out(s);
    for (char& c : out) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    return out;
}

/// Optimal string alignment distance (Levenshtein plus adjacent transpositions), ignoring
/// case: "endtiem" and "End_Time" are both one or two edits from "end_time".
std::size_t edit_distance(std::string_view a_in, std::string_view b_in) {
    const std::string a = lower(a_in), b = lower(b_in);
    std::vector<std::vector<std::size_t>> d(a.size() + 1, std::vector<std::size_t>(b.size() + 1));
    for (std::size_t i = 0; i <= a.size(); ++i) d[i][0] = i;
    for (std::size_t j = 0; j <= b.size(); ++j) d[0][j] = j;
    for (std::size_t i = 1; i <= a.size(); ++i) {
        for (std::size_t j = 1; j <= b.size(); ++j) {
            const std::size_t cost = a[i - 1] == b[j - 1] ? 0 : 1;
            d[i][j] = std::min({d[i - 1][j] + 1, d[i][j - 1] + 1, d[i - 1][j - 1] + cost});
            if (i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1]) {
                d[i][j] = std::min(d[i][j], d[i - 2][j - 2] + 1);
            }
        }
    }
    return d[a.size()][b.size()];
}

/// " (did you mean "x"?)" for the closest name within a third of its length, else "".
std::string suggestion(std::string_view found, std::span<const char* const> names) {
    const char* best = nullptr;
    std::size_t best_distance = std::numeric_limits<std::size_t>::max();
    for (const char* name : names) {
        const std::size_t limit = std::max<std::size_t>(1, std::string_view(name).size() / 3);
        const std::size_t d = edit_distance(found, name);
        if (d <= limit && d < best_distance) {
            best = name;
            best_distance = d;
        }
    }
    return best ? " (did you mean " + in_quotes(best) + "?)" : std::string();
}


// ---- JSON text -> document, with positions and paths for every kind of failure. ----

/// Builds the document like nlohmann's DOM parser but knows the JSON path of the value being
/// read, so duplicate keys (which nlohmann silently overwrites) and numbers that overflow a
/// double are reported at their path.
constexpr std::size_t kMaxSceneDepth = 64;  ///< objects and arrays nested in a scene (the schema needs 6)

class DomBuilder final : public json::json_sax_t {
  public:
    explicit DomBuilder(json& root) : m_root(root) {}

    bool null() override { return insert(nullptr); }
    bool boolean(bool v) override { return insert(v); }
    bool number_integer(number_integer_t v) override { return insert(v); }
    bool number_unsigned(number_unsigned_t v) override { return insert(v); }
    bool number_float(number_float_t v, const string_t& /*text*/) override { return insert(v); }
    bool string(string_t& v) override { return insert(std::move(v)); }
    bool binary(binary_t& /*v*/) override { return false; }  // not produced by JSON text
    bool start_object(std::size_t /*elements*/) override { return open(json::object()); }
    bool start_array(std::size_t /*elements*/) override { return open(json::array()); }
    bool end_object() override { return close(); }
    bool end_array() override { return close(); }

    bool key(string_t& k) override {
        if (m_stack.back().value->contains(k)) {
            duplicate_key = k;
            error_path = child(m_stack.back().path, k);
            return false;
        }
        m_key = k;
        return true;
    }

    bool parse_error(std::size_t position, const std::string& last_token,
                     const json::exception& ex) override {
        error_position = position;
        error_id = ex.id;
        error_what = ex.what();
        error_token = last_token;
        error_path = value_path();
        return false;
    }

    std::optional<std::string> duplicate_key;
    bool too_deep = false;
    std::string error_path;
    std::size_t error_position = 0;
    int error_id = 0;
    std::string error_what, error_token;

  private:
    struct Frame {
        json* value;
        std::string path;
    };

    std::string value_path() const {
        if (m_stack.empty()) return "";
        const Frame& top = m_stack.back();
        return top.value->is_array() ? child(top.path, top.value->size()) : child(top.path, m_key);
    }

    json* place(json v) {
        if (m_stack.empty()) {
            m_root = std::move(v);
            return &m_root;
        }
        json& top = *m_stack.back().value;
        if (top.is_array()) {
            top.push_back(std::move(v));
            return &top.back();
        }
        json& slot = top[m_key];
        slot = std::move(v);
        return &slot;
    }

    template <class V>
    bool insert(V&& v) {
        place(json(std::forward<V>(v)));
        return true;
    }

    bool open(json v) {
        if (m_stack.size() >= kMaxSceneDepth) {  // each level holds its path: memory grows as depth^2
            too_deep = true;
            error_path = value_path();
            return false;
        }
        std::string path = value_path();
        json* p = place(std::move(v));
        m_stack.push_back({p, std::move(path)});
        return true;
    }

    bool close() {
        m_stack.pop_back();
        return true;
    }

    json& m_root;
    std::vector<Frame> m_stack;
    std::string m_key;
};

/// 1-based line and column (in characters, not bytes) of byte offset `offset`.
std::pair<std::size_t, std::size_t> line_column(const std::string& text, std::size_t offset) {
    std::size_t line = 1, column = 1;
    for (std::size_t i = 0; i < offset && i < text.size(); ++i) {
        if (text[i] == '\n') {
            ++line;
            column = 1;
        } else if ((static_cast<unsigned char>(text[i]) & 0xC0) != 0x80) {
            ++column;
        }
    }
    return {line, column};
}

bool is_word_char(char c) {
    return std::isalnum(static_cast<unsigned char>(c)) || c == '_';
}

/// Start of the complete token that ends at `last` (nlohmann reports the position after it).
std::size_t token_start(const std::string& text, std::size_t last) {
    if (last >= text.size()) return last;
    if (text[last] == '"') {  // back to the opening quote: one not escaped by a backslash
        for (std::size_t k = last; k-- > 0 && text[k] != '\n';) {
            std::size_t backslashes = 0;
            while (backslashes < k && text[k - 1 - backslashes] == '\\') ++backslashes;
            if (text[k] == '"' && backslashes % 2 == 0) return k;
        }
        return last;
    }
    std::size_t k = last;
    while (k > 0 && (is_word_char(text[k - 1]) ||
                     std::string_view(".+-").find(text[k - 1]) != std::string_view::npos)) {
        --k;
    }
    return is_word_char(text[last]) ? k : last;
}

/// A short reason for a syntax error, and the byte offset it is about: nlohmann's own reason
/// without its prefix and its "last read" echo (which can hold half a UTF-8 sequence), or a
/// plainer one for the common mistakes.
std::string syntax_reason(const std::string& text, std::size_t& offset, const std::string& what) {
    std::string reason = what;
    if (const auto dash = reason.find(" - "); dash != std::string::npos) {
        reason = reason.substr(dash + 3);
    }
    if (const auto echo = reason.find("; last read: '"); echo != std::string::npos) {
        const auto rest = reason.rfind("'; expected ");
        if (rest != std::string::npos && rest > echo) {
            reason.erase(echo, rest + 1 - echo);
        } else {
            reason.erase(echo);
        }
    }
    // After a member or an element, nlohmann names only the closing bracket as expected.
    for (const char* close : {"'}'", "']'"}) {
        const std::string tail = std::string("; expected ") + close;
        if (reason.ends_with(tail)) reason.insert(reason.size() - 3, "',' or ");
    }
    const bool at_end = offset >= text.size();
    if (reason.starts_with("unexpected ") && !at_end) offset = token_start(text, offset);
    if (reason.starts_with("unexpected end of input")) {
        if (text.find_first_not_of(" \t\r\n") == std::string::npos) {
            return "the file is empty; expected a JSON object";
        }
        reason.replace(0, 23, "unexpected end of file");
    }
    if (reason.find("ill-formed UTF-8") != std::string::npos && !at_end &&
        (static_cast<unsigned char>(text[offset]) & 0x80) == 0) {
        // Detected on the byte after an incomplete sequence: point at the sequence's start.
        while (offset > 0 && (static_cast<unsigned char>(text[offset - 1]) & 0xC0) == 0x80)
            --offset;
        if (offset > 0 && (static_cast<unsigned char>(text[offset - 1]) & 0xC0) == 0xC0) --offset;
        return "invalid UTF-8 in a string (the file must be UTF-8)";
    }

    const char c = at_end ? '\0' : text[offset];
    if (c == '/') return "comments are not allowed in JSON";
    if (c == '\'') return "strings must be in double quotes";
    if (reason.find("; expected end of input") != std::string::npos) {
        return "unexpected text after the end of the top-level value";
    }
    if (c == '}' || c == ']') {
        std::size_t p = offset;
        while (p > 0 && std::isspace(static_cast<unsigned char>(text[p - 1]))) --p;
        if (p > 0 && text[p - 1] == ',') {
            offset = p - 1;
            return std::string("trailing comma before '") + c + "' (not allowed in JSON)";
        }
    }
    if (reason.starts_with("invalid literal")) {
        if (c == '.' || c == '+') return "invalid number (JSON numbers start with a digit or '-')";
        std::size_t begin = offset, end = offset;
        while (end < text.size() && is_word_char(text[end])) ++end;
        while (begin > 0 && is_word_char(text[begin - 1])) --begin;
        const std::string word = text.substr(begin, end - begin);
        const std::string w = lower(word);
        if (w == "nan" || w == "inf" || w == "infinity") {
            return "NaN and Infinity are not JSON numbers";
        }
        if (!word.empty()) {
            offset = begin;
            return "invalid word " + in_quotes(truncate(word, 40)) +
                   " (strings need double quotes; the literals are true, false and null)";
        }
    }
    if (reason.find("control character U+000A") != std::string::npos) {
        return "line break inside a string (missing closing quote?)";
    }
    return reason;
}

json parse_document(const std::string& text, const std::string& file) {
    json doc;
    DomBuilder builder(doc);
    if (json::sax_parse(text, &builder, json::input_format_t::json, /*strict=*/true,
                        /*ignore_comments=*/false)) {
        return doc;
    }
    if (builder.duplicate_key) {
        throw SceneError(file, builder.error_path,
                         "duplicate key " + in_quotes(*builder.duplicate_key),
                         "each key at most once per object");
    }
    if (builder.too_deep) {
        throw SceneError(file, shown(builder.error_path).substr(0, 200), "objects or arrays nested more than 64 deep",
                         "a scene nests at most 64 levels (its schema needs 6)");
    }
    if (builder.error_id == 406) {  // out_of_range.406: the number overflows a double
        throw SceneError(file, shown(builder.error_path), truncate(builder.error_token),
                         "a finite number (this one overflows a double)");
    }
    // nlohmann reports the count of characters read: the offending one is the last of them.
    std::size_t offset = builder.error_position > 0 ? builder.error_position - 1 : 0;
    const std::string reason = syntax_reason(text, offset, builder.error_what);
    const auto [line, column] = line_column(text, offset);
    throw InputError(file + ": JSON syntax error at line " + std::to_string(line) + ", column " +
                     std::to_string(column) + ": " + reason);
}

}  // namespace sph::scene_detail
