// penumbra::scene OBJ loading — Wavefront OBJ files as penumbra scenes, via tinyobjloader.
// Part of penumbra::support (support/include/; a core install has none of it, see CMakeLists.txt:
// PENUMBRA_BUILD_SUPPORT). CMake target penumbra::support links tinyobjloader and stb.
//
// Integration: needs tinyobjloader's header <tiny_obj_loader.h> and its compiled library: link
// tinyobjloader (CMake target tinyobjloader::tinyobjloader, or -ltinyobjloader). Do NOT define
// TINYOBJLOADER_IMPLEMENTATION (the library holds it), nor TINYOBJLOADER_USE_DOUBLE unless you
// link tinyobjloader_double instead. Also uses scene.hpp (GLM).
// Produces a Scene like the builtins: {ground, object} (or {object}) with the default camera and
// light, so `load("builtin:grass")` and `load("meshes/spot.obj")` are interchangeable.
// What loadObj does with the file:
//   - every shape/group goes into one object mesh named after the file's stem;
//   - only positions and normals are used (texture coordinates and materials are ignored; a
//     missing .mtl is not an error);
//   - polygons are triangulated keeping their winding: quads along the shorter diagonal (as
//     tinyobjloader does), larger polygons by ear clipping in the polygon's Newell plane;
//   - faces of fewer than 3 corners and triangles that repeat a vertex index are dropped
//     (counted in ObjReport), unreferenced vertices are removed;
//   - exact duplicate triangles (the same three file positions in the same cyclic order as an
//     earlier triangle, whatever the vertex indices) are removed and counted: a duplicate blocks
//     the same light, so visibility is unchanged, while every block would test it again. The
//     reversed winding is not a duplicate: a front/back pair is a two-sided sheet and closes the
//     edge topology (isClosed);
//   - file normals are kept only if every use of a position names the same normal (one normal
//     per vertex); otherwise, or if absent, smooth angle-weighted normals are computed;
//   - closed = every edge shared by exactly two triangles with opposite orientation; a closed
//     mesh with negative signed volume (inside-out) is flipped so that it faces outward;
//   - coordinates are parsed, triangulated and normalised in double and only then rounded to
//     float, so a mesh far from the origin keeps its shape (a float at 1e8 is 8 apart).
// Before tinyobjloader sees the text, a validating pass reads every statement loadObj uses and
// rejects, naming the line number and the offending text: numbers that do not parse (strict
// decimal: `nan`, `inf`, hex and trailing garbage are errors, where tinyobjloader would read 0),
// coordinates beyond float range, `v`/`vn` lines with fewer than 3 numbers, face indices that are
// 0, overflow int, or lie outside the vertices / texture coordinates / normals of the file
// (negative = relative to those defined so far), and faces of more than 255 corners. Only
// `v`, `vt`, `vn`, `f`, `o` and `g` statements reach tinyobjloader; everything else (materials,
// smoothing groups, lines, points, tinyobjloader's `vw`/`t` extensions) is ignored; `v`/`vt`/`vn`
// values reach it re-printed in shortest round-trip form, never as the file's text (its number
// parser overflows int on exponents like `0e-2147483648`, found by obj_fuzz).
// Failures throw penumbra::Error naming the path (or parseObj's name) and the reason; nothing
// else escapes (tests/fuzz/obj_fuzz.cpp checks that on arbitrary bytes). What was dropped or
// removed is counted in an ObjReport (the overloads that take one), with one warning line per
// kind; ObjOptions::progress reports progress and can cancel.
#ifndef PENUMBRA_SCENE_OBJ_HPP
#define PENUMBRA_SCENE_OBJ_HPP

#include <penumbra/error.hpp>
#include <penumbra/scene/scene.hpp>

#include <tiny_obj_loader.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cfloat>
#include <charconv>
#include <climits>
#include <cstdint>
#include <fstream>
#include <functional>
#include <sstream>
#include <string>
#include <string_view>
#include <system_error>
#include <utility>
#include <vector>

namespace penumbra::scene {

/// Value-initialised = defaults.
struct ObjOptions {
    bool ground = true;     // add a ground plane under the object
    bool normalize = true;  // scale uniformly so the largest extent is 1, centre on the y axis
                            // and rest on the ground y = 0 (in double); otherwise keep file
                            // coordinates (rounded to float) and put the ground (if any) at the
                            // object's lowest y
    bool remove_duplicate_triangles = true;  // false keeps them (still counted in ObjReport)
    /// Called on the calling thread with the fraction done (nondecreasing, 0 first, 1 last): at
    /// each stage and every 65536 lines or faces. Returning false cancels: loading throws
    /// penumbra::Error saying so. Empty = no calls.
    std::function<bool(double fraction)> progress = nullptr;
};

/// What loading changed that the Scene cannot show. Reset by every load that fills it.
struct ObjReport {
    size_t short_faces = 0;               // `f` statements with fewer than 3 corners, dropped
    size_t repeated_index_triangles = 0;  // triangles naming a vertex twice, dropped
    size_t duplicate_triangles = 0;       // exact duplicates (see the summary), removed unless
                                          // ObjOptions::remove_duplicate_triangles is false
    /// One line per nonzero count above, naming the file and the count, in that order.
    std::vector<std::string> warnings;
};

/// Loads a Wavefront OBJ file as a Scene (see the summary above for what is kept and how).
/// Throws penumbra::Error naming `path` when the file cannot be opened or read, a statement is
/// malformed (the message names its line and value, see the summary), no triangle is left, all
/// used vertices coincide (in double; with normalize = false, in float), or progress cancels.
inline Scene loadObj(const std::string& path, const ObjOptions& options = {});
/// The same, filling `report`.
inline Scene loadObj(const std::string& path, const ObjOptions& options, ObjReport& report);

/// The same from OBJ text in memory (no file access; `mtllib` is ignored like every material).
/// `name` names the mesh (its stem, as for a path) and the errors.
inline Scene parseObj(const std::string& text, const std::string& name = "memory.obj",
                      const ObjOptions& options = {});
/// The same, filling `report`.
inline Scene parseObj(const std::string& text, const std::string& name, const ObjOptions& options,
                      ObjReport& report);

/// "builtin:NAME" -> builtin(NAME); anything else is a path for loadObj with default options.
inline Scene load(const std::string& spec);

// =============================================================================================
// Implementation

namespace detail {

/// Triangulates one polygon given its corner positions, appending corner-index triples
/// (0 .. n-1) that keep the polygon's winding, so closed-mesh orientation survives.
inline void triangulatePolygon(const std::vector<glm::dvec3>& corners,
                               std::vector<std::array<uint32_t, 3>>& triangles) {
    const uint32_t n = static_cast<uint32_t>(corners.size());
    if (n < 3) return;
    if (n == 3) {
        triangles.push_back({0, 1, 2});
        return;
    }
    if (n == 4) {
        // Shorter diagonal: the better split of a non-planar quad, and tinyobjloader's choice.
        const glm::dvec3 d02 = corners[2] - corners[0], d13 = corners[3] - corners[1];
        if (glm::dot(d02, d02) <= glm::dot(d13, d13)) {
            triangles.push_back({0, 1, 2});
            triangles.push_back({0, 2, 3});
        } else {
            triangles.push_back({0, 1, 3});
            triangles.push_back({1, 2, 3});
        }
        return;
    }
    // Newell's normal is robust for non-planar and concave polygons.
    glm::dvec3 normal(0.0);
    for (uint32_t i = 0; i < n; ++i) {
        const glm::dvec3 a = corners[i], b = corners[(i + 1) % n];
        normal += glm::dvec3((a.y - b.y) * (a.z + b.z), (a.z - b.z) * (a.x + b.x),
                             (a.x - b.x) * (a.y + b.y));
    }
    std::vector<uint32_t> remaining(n);
    for (uint32_t i = 0; i < n; ++i) remaining[i] = i;
    // Ear clipping is O(n^2) per ear; huge polygons (rare in practice) fall back to a fan.
    const bool clip_ears = glm::length(normal) > 0.0 && n <= 256;
    auto cornerAt = [&](uint32_t k) { return corners[remaining[k]]; };
    auto side = [&](const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& p) {
        return glm::dot(glm::cross(b - a, p - a), normal);
    };
    while (remaining.size() > 3) {
        const uint32_t m = static_cast<uint32_t>(remaining.size());
        uint32_t ear = 0;  // fan from the first corner if no ear is found
        if (clip_ears) {
            for (uint32_t k = 0; k < m; ++k) {
                const glm::dvec3 a = cornerAt((k + m - 1) % m), b = cornerAt(k), c = cornerAt((k + 1) % m);
                if (side(a, b, c) <= 0.0) continue;  // reflex or degenerate corner
                bool contains_other = false;
                for (uint32_t other = 0; other < m && !contains_other; ++other) {
                    if (other == k || other == (k + 1) % m || other == (k + m - 1) % m) continue;
                    const glm::dvec3 p = cornerAt(other);
                    contains_other = side(a, b, p) >= 0.0 && side(b, c, p) >= 0.0 && side(c, a, p) >= 0.0;
                }
                if (!contains_other) {
                    ear = k;
                    break;
                }
            }
        }
        triangles.push_back({remaining[(ear + m - 1) % m], remaining[ear], remaining[(ear + 1) % m]});
        remaining.erase(remaining.begin() + ear);
    }
    triangles.push_back({remaining[0], remaining[1], remaining[2]});
}

inline bool isObjSpace(char c) { return c == ' ' || c == '\t'; }

/// Splits a line at spaces and tabs.
inline void splitObjTokens(std::string_view line, std::vector<std::string_view>& tokens) {
    tokens.clear();
    size_t i = 0;
    while (i < line.size()) {
        while (i < line.size() && isObjSpace(line[i])) ++i;
        const size_t start = i;
        while (i < line.size() && !isObjSpace(line[i])) ++i;
        if (i > start) tokens.push_back(line.substr(start, i - start));
    }
}

/// Quotes a token for a message: printable ASCII as is, other bytes as \xNN, long ones cut.
inline std::string quoteObjToken(std::string_view token) {
    static const char kHex[] = "0123456789abcdef";
    std::string out = "'";
    for (size_t i = 0; i < token.size() && i < 40; ++i) {
        const auto c = static_cast<unsigned char>(token[i]);
        if (c >= 0x20 && c < 0x7f) {
            out += static_cast<char>(c);
        } else {
            out += "\\x";
            out += kHex[c >> 4];
            out += kHex[c & 15];
        }
    }
    if (token.size() > 40) out += "...";
    return out + "'";
}

/// Strict decimal number: [+-]? (digits [. digits] | . digits) ([eE] [+-]? digits), parsed
/// locale-independently. False for anything else (nan, inf, hex, empty, trailing characters).
inline bool parseObjNumber(std::string_view token, double& value, bool& out_of_range) {
    out_of_range = false;
    size_t i = 0;
    const size_t n = token.size();
    auto digit = [&](size_t k) { return k < n && token[k] >= '0' && token[k] <= '9'; };
    if (i < n && (token[i] == '+' || token[i] == '-')) ++i;
    size_t digits = 0;
    while (digit(i)) ++i, ++digits;
    if (i < n && token[i] == '.') {
        ++i;
        while (digit(i)) ++i, ++digits;
    }
    if (digits == 0) return false;
    if (i < n && (token[i] == 'e' || token[i] == 'E')) {
        ++i;
        if (i < n && (token[i] == '+' || token[i] == '-')) ++i;
        if (!digit(i)) return false;
        while (digit(i)) ++i;
    }
    if (i != n) return false;
    const char* first = token.data() + (token[0] == '+' ? 1 : 0);  // from_chars takes no '+'
    const std::from_chars_result result = std::from_chars(first, token.data() + n, value);
    if (result.ec == std::errc::result_out_of_range) {
        // A zero mantissa with a huge exponent (0e-99999) is zero, not out of range.
        bool zero = true;
        for (size_t k = 0; k < n && token[k] != 'e' && token[k] != 'E'; ++k)
            if (token[k] >= '1' && token[k] <= '9') zero = false;
        if (zero) {
            value = token[0] == '-' ? -0.0 : 0.0;
            return true;
        }
        out_of_range = true;
        return true;
    }
    return result.ec == std::errc() && result.ptr == token.data() + n;
}

/// Strict integer index [+-]?digits that fits an int (tinyobjloader parses it with atoi).
inline bool parseObjIndex(std::string_view token, long long& value, bool& overflow) {
    overflow = false;
    size_t i = 0;
    bool negative = false;
    if (i < token.size() && (token[i] == '+' || token[i] == '-')) negative = token[i++] == '-';
    if (i == token.size()) return false;
    long long magnitude = 0;
    for (; i < token.size(); ++i) {
        if (token[i] < '0' || token[i] > '9') return false;
        magnitude = magnitude * 10 + (token[i] - '0');
        if (magnitude > 1ll + INT_MAX) overflow = true, magnitude = 1ll + INT_MAX;
    }
    value = negative ? -magnitude : magnitude;
    if (value > INT_MAX || value < INT_MIN) overflow = true;
    return true;
}

/// ObjOptions::progress with the cancellation turned into penumbra::Error.
struct ObjProgress {
    const std::function<bool(double)>& callback;
    const std::string& where;
    void operator()(double fraction) const {
        if (callback && !callback(fraction))
            ::penumbra::detail::fail(where, "cancelled by the progress callback at ", 100.0 * fraction, "%");
    }
};
/// Calls per stage loop: one every 2^16 lines or faces.
inline constexpr size_t kObjProgressMask = 0xffff;

/// The validating pass (see the header summary): returns the text tinyobjloader gets, with the
/// same line numbering (dropped statements become empty lines); throws naming line and value.
/// Also hands back every `v` position in double (tinyobjloader keeps floats) and the number of
/// faces of fewer than 3 corners (tinyobjloader drops them), and reports progress 0 .. `done`.
inline std::string validateObjText(const std::string& text, const std::string& where,
                                   std::vector<glm::dvec3>& positions, size_t& short_faces,
                                   const ObjProgress& progress, double done) {
    positions.clear();
    short_faces = 0;
    // Lines end at \n, \r\n or a lone \r, as in tinyobjloader.
    std::vector<std::string_view> lines;
    {
        const std::string_view all(text);
        size_t start = 0;
        for (size_t i = 0; i < all.size(); ++i) {
            if (all[i] != '\n' && all[i] != '\r') continue;
            lines.push_back(all.substr(start, i - start));
            if (all[i] == '\r' && i + 1 < all.size() && all[i + 1] == '\n') ++i;
            start = i + 1;
        }
        if (start < all.size()) lines.push_back(all.substr(start));
    }
    std::vector<std::string_view> tokens;
    // Pass 1: how many v / vt / vn the file defines (positive face indices may point forward).
    size_t totals[3] = {0, 0, 0};
    for (std::string_view line : lines) {
        size_t i = 0;
        while (i < line.size() && isObjSpace(line[i])) ++i;
        if (i >= line.size() || line[i] != 'v') continue;
        const std::string_view rest = line.substr(i + 1);
        if (!rest.empty() && isObjSpace(rest[0])) ++totals[0];
        else if (rest.size() >= 2 && rest[0] == 't' && isObjSpace(rest[1])) ++totals[1];
        else if (rest.size() >= 2 && rest[0] == 'n' && isObjSpace(rest[1])) ++totals[2];
    }
    size_t defined[3] = {0, 0, 0};
    static const char* const kKinds[3] = {"vertex", "texture coordinate", "normal"};
    static const char* const kKindsPlural[3] = {"vertices", "texture coordinates", "normals"};
    std::string out;
    out.reserve(text.size() + 1);
    for (size_t l = 0; l < lines.size(); ++l) {
        const size_t line_number = l + 1;
        if ((l & kObjProgressMask) == kObjProgressMask) progress(done * double(l) / double(lines.size()));
        splitObjTokens(lines[l], tokens);
        auto failAt = [&](const auto&... what) { ::penumbra::detail::fail(where, "line ", line_number, ": ", what...); };
        const std::string_view keyword = tokens.empty() ? std::string_view() : tokens[0];
        int kind = -1;
        if (keyword == "v") kind = 0;
        else if (keyword == "vt") kind = 1;
        else if (keyword == "vn") kind = 2;
        if (kind >= 0) {
            const size_t count = tokens.size() - 1;
            const size_t min_count = kind == 1 ? 1 : 3, max_count = kind == 0 ? 7 : 3;
            const size_t number = defined[kind] + 1;
            // tinyobjloader gets the values re-printed (shortest round-trip form), never the
            // file's text: its own number parser overflows int on long exponents.
            out.append(keyword.data(), keyword.size());
            if (count < min_count)
                failAt("'", keyword, "' (", kKinds[kind], " ", number, ") needs ", min_count == 1 ? "a value" : "3 coordinates",
                       ", found ", count);
            if (count > max_count)
                failAt("'", keyword, "' (", kKinds[kind], " ", number, ") has ", count, " values, at most ", max_count);
            double position[3] = {0.0, 0.0, 0.0};
            for (size_t t = 1; t < tokens.size(); ++t) {
                double value = 0;
                bool out_of_range = false;
                if (!parseObjNumber(tokens[t], value, out_of_range)) {
                    const std::string word(tokens[t].substr(tokens[t][0] == '+' || tokens[t][0] == '-' ? 1 : 0));
                    std::string lower;
                    for (char c : word) lower += static_cast<char>(c >= 'A' && c <= 'Z' ? c - 'A' + 'a' : c);
                    if (lower.rfind("nan", 0) == 0 || lower.rfind("inf", 0) == 0)
                        failAt(kKinds[kind], " ", number, " has a NaN or infinite coordinate ", quoteObjToken(tokens[t]));
                    failAt(kKinds[kind], " ", number, ": ", quoteObjToken(tokens[t]), " is not a number");
                }
                if (out_of_range || std::abs(value) > double(FLT_MAX))
                    failAt(kKinds[kind], " ", number, ": ", quoteObjToken(tokens[t]),
                           " is beyond float range (|value| <= 3.4e38)");
                if (t <= 3) position[t - 1] = value;
                char printed[32];
                const std::to_chars_result written = std::to_chars(printed, printed + sizeof printed, value);
                out += ' ';
                out.append(printed, written.ptr);
            }
            if (kind == 0) positions.emplace_back(position[0], position[1], position[2]);
            ++defined[kind];
            out += '\n';
            continue;
        } else if (keyword == "f") {
            if (tokens.size() - 1 > 255) failAt("a face of ", tokens.size() - 1, " corners (at most 255)");
            if (tokens.size() - 1 < 3) ++short_faces;
            for (size_t t = 1; t < tokens.size(); ++t) {
                // v, v/vt, v//vn or v/vt/vn
                const std::string_view corner = tokens[t];
                std::string_view parts[3];
                size_t part_count = 0, start = 0;
                for (size_t i = 0; i <= corner.size(); ++i) {
                    if (i < corner.size() && corner[i] != '/') continue;
                    if (part_count == 3) failAt("face corner ", quoteObjToken(corner), " has more than 3 indices");
                    parts[part_count++] = corner.substr(start, i - start);
                    start = i + 1;
                }
                for (size_t k = 0; k < part_count; ++k) {
                    if (parts[k].empty() && k > 0 && !(k == 1 && part_count == 3)) {
                        failAt("face corner ", quoteObjToken(corner), " has an empty ", kKinds[k], " index");
                    }
                    if (parts[k].empty() && k > 0) continue;  // v//vn
                    long long index = 0;
                    bool overflow = false;
                    if (!parseObjIndex(parts[k], index, overflow))
                        failAt("face corner ", quoteObjToken(corner), ": ", quoteObjToken(parts[k]), " is not a ",
                               kKinds[k], " index");
                    if (overflow)
                        failAt("face corner ", quoteObjToken(corner), ": ", kKinds[k], " index ",
                               quoteObjToken(parts[k]), " overflows int");
                    if (index == 0)
                        failAt("face corner ", quoteObjToken(corner), ": ", kKinds[k], " index 0 (OBJ indices start at 1)");
                    if (index > 0 && static_cast<size_t>(index) > totals[k])
                        failAt("face uses ", kKinds[k], " ", index, " but the file has ", totals[k], " ", kKindsPlural[k]);
                    if (index < 0 && static_cast<size_t>(-index) > defined[k])
                        failAt("face corner ", quoteObjToken(corner), ": relative ", kKinds[k], " index ", index,
                               " reaches before the first (", defined[k], " defined so far)");
                }
            }
        } else if (keyword != "o" && keyword != "g") {
            out += '\n';  // ignored statement, comment or blank line
            continue;
        }
        out.append(lines[l].data(), lines[l].size());
        out += '\n';
    }
    return out;
}

inline std::string trimTrailingSpace(std::string text) {
    while (!text.empty() && (text.back() == '\n' || text.back() == '\r' || text.back() == ' '))
        text.pop_back();
    return text;
}

inline std::string fileStem(const std::string& path) {
    const size_t slash = path.find_last_of("/\\");
    std::string name = slash == std::string::npos ? path : path.substr(slash + 1);
    const size_t dot = name.find_last_of('.');
    if (dot != std::string::npos && dot > 0) name.resize(dot);
    return name.empty() ? std::string("obj") : name;
}

/// Equal positions get equal ids (exact comparison; -0 equals 0, NaN cannot occur).
inline std::vector<uint32_t> positionIds(const std::vector<glm::dvec3>& positions) {
    auto less = [](const glm::dvec3& a, const glm::dvec3& b) {
        return a.x < b.x || (a.x == b.x && (a.y < b.y || (a.y == b.y && a.z < b.z)));
    };
    std::vector<uint32_t> order(positions.size());
    for (size_t v = 0; v < order.size(); ++v) order[v] = static_cast<uint32_t>(v);
    std::sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) { return less(positions[a], positions[b]); });
    std::vector<uint32_t> ids(positions.size());
    uint32_t id = 0;
    for (size_t k = 0; k < order.size(); ++k) {
        if (k > 0 && less(positions[order[k - 1]], positions[order[k]])) ++id;
        ids[order[k]] = id;
    }
    return ids;
}

/// Marks exact duplicate triangles (same position ids in the same cyclic order as an earlier
/// triangle); the first occurrence stays, so the result does not depend on sorting.
inline size_t markDuplicateTriangles(const std::vector<std::array<uint32_t, 3>>& triangles,
                                     const std::vector<glm::dvec3>& positions, std::vector<bool>& duplicate) {
    const std::vector<uint32_t> ids = positionIds(positions);
    std::vector<std::array<uint32_t, 3>> keys(triangles.size());
    for (size_t t = 0; t < triangles.size(); ++t) {
        const std::array<uint32_t, 3> id = {ids[triangles[t][0]], ids[triangles[t][1]], ids[triangles[t][2]]};
        // The least of the three rotations: rotations of one triangle get one key, the
        // reversed winding another.
        keys[t] = id;
        for (size_t r = 1; r < 3; ++r) keys[t] = std::min(keys[t], {id[r], id[(r + 1) % 3], id[(r + 2) % 3]});
    }
    std::vector<uint32_t> order(triangles.size());
    for (size_t t = 0; t < order.size(); ++t) order[t] = static_cast<uint32_t>(t);
    std::sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) { return keys[a] < keys[b] || (keys[a] == keys[b] && a < b); });
    duplicate.assign(triangles.size(), false);
    size_t count = 0;
    for (size_t k = 1; k < order.size(); ++k) {
        if (keys[order[k]] == keys[order[k - 1]]) {
            duplicate[order[k]] = true;
            ++count;
        }
    }
    return count;
}

inline Scene loadObjText(const std::string& text, const std::string& where, const std::string& stem,
                         const ObjOptions& options, ObjReport& report) {
    report = ObjReport{};
    const ObjProgress progress{options.progress, where};
    progress(0.0);
    // tinyobjloader's positions are floats: ours come from the validating pass, in double.
    std::vector<glm::dvec3> file_positions;
    std::istringstream stream(validateObjText(text, where, file_positions, report.short_faces, progress, 0.4));
    tinyobj::attrib_t attrib;
    std::vector<tinyobj::shape_t> shapes;
    std::vector<tinyobj::material_t> materials;
    std::string warnings, errors;
    // No material reader: materials are ignored, and parsing touches no file. triangulate =
    // false: we triangulate ourselves so winding (hence closedness) is preserved whichever
    // triangulator the installed tinyobjloader was built with. Its warnings are not read: with
    // the statements it gets, the only one is for short faces, which the pass counts.
    const bool parsed = tinyobj::LoadObj(&attrib, &shapes, &materials, &warnings, &errors, &stream,
                                         /*readMatFn=*/nullptr, /*triangulate=*/false);
    PENUMBRA_CHECK(parsed, where, "parse error: ", detail::trimTrailingSpace(errors));
    progress(0.7);

    const size_t vertex_count = attrib.vertices.size() / 3;
    const size_t normal_count = attrib.normals.size() / 3;
    PENUMBRA_CHECK(vertex_count == file_positions.size(), where, "tinyobjloader read ", vertex_count,
                   " vertices, the validating pass ", file_positions.size());
    size_t face_count = 0, faces_done = 0;
    for (const tinyobj::shape_t& shape : shapes) face_count += shape.mesh.num_face_vertices.size();

    // Triangles in file vertex indices, plus the normal index each corner named (-1 if none).
    std::vector<std::array<uint32_t, 3>> triangles;
    std::vector<std::array<int, 3>> triangle_normals;
    std::vector<std::array<uint32_t, 3>> local;
    std::vector<glm::dvec3> corners;
    for (const tinyobj::shape_t& shape : shapes) {
        const std::vector<tinyobj::index_t>& indices = shape.mesh.indices;
        size_t offset = 0;
        for (size_t face = 0; face < shape.mesh.num_face_vertices.size(); ++face) {
            if ((++faces_done & kObjProgressMask) == 0) progress(0.7 + 0.2 * double(faces_done) / double(face_count));
            const size_t n = shape.mesh.num_face_vertices[face];
            // tinyobjloader stores face sizes as unsigned char: a face of 256+ corners would
            // desynchronise the index stream, which this catches below.
            PENUMBRA_CHECK(offset + n <= indices.size(), where, "malformed face data in shape '",
                           shape.name, "' (a face with more than 255 corners?)");
            corners.clear();
            for (size_t k = 0; k < n; ++k) {
                const int v = indices[offset + k].vertex_index;
                PENUMBRA_CHECK(v >= 0 && static_cast<size_t>(v) < vertex_count, where, "face ", face + 1,
                               " of shape '", shape.name, "' uses vertex ", v + 1, " but the file has ",
                               vertex_count, " vertices");
                corners.push_back(file_positions[static_cast<size_t>(v)]);
            }
            local.clear();
            detail::triangulatePolygon(corners, local);
            for (const std::array<uint32_t, 3>& t : local) {
                std::array<uint32_t, 3> triangle{};
                std::array<int, 3> normals{};
                for (size_t k = 0; k < 3; ++k) {
                    const tinyobj::index_t& corner = indices[offset + t[k]];
                    triangle[k] = static_cast<uint32_t>(corner.vertex_index);
                    normals[k] = corner.normal_index;
                }
                // A repeated index is no triangle at all and would poison the edge topology.
                if (triangle[0] == triangle[1] || triangle[1] == triangle[2] || triangle[2] == triangle[0]) {
                    ++report.repeated_index_triangles;
                    continue;
                }
                triangles.push_back(triangle);
                triangle_normals.push_back(normals);
            }
            offset += n;
        }
        PENUMBRA_CHECK(offset == indices.size(), where, "malformed face data in shape '", shape.name,
                       "' (a face with more than 255 corners?)");
    }
    PENUMBRA_CHECK(!triangles.empty(), where, "no triangles (", vertex_count, " vertices, ",
                   shapes.size(), " shapes)");
    PENUMBRA_CHECK(triangles.size() * 3 <= detail::kMaxSceneVertices, where, "too many triangles");

    std::vector<bool> duplicate;
    report.duplicate_triangles = markDuplicateTriangles(triangles, file_positions, duplicate);
    if (report.duplicate_triangles > 0 && options.remove_duplicate_triangles) {
        size_t kept = 0;
        for (size_t t = 0; t < triangles.size(); ++t) {
            if (duplicate[t]) continue;
            triangles[kept] = triangles[t];
            triangle_normals[kept++] = triangle_normals[t];
        }
        triangles.resize(kept);
        triangle_normals.resize(kept);
    }
    progress(0.95);

    // Keep used vertices only, in file order, so the mesh bounds are the object's.
    constexpr uint32_t kUnused = UINT32_MAX;
    std::vector<uint32_t> remap(vertex_count, kUnused);
    for (const auto& triangle : triangles)
        for (uint32_t v : triangle) remap[v] = 0;
    std::vector<size_t> used;  // file vertex of each mesh vertex
    for (size_t v = 0; v < vertex_count; ++v) {
        if (remap[v] == kUnused) continue;
        remap[v] = static_cast<uint32_t>(used.size());
        used.push_back(v);
    }
    // Normalised in double, rounded once: the file's digits survive any offset from the origin.
    glm::dvec3 lo(DBL_MAX), hi(-DBL_MAX);
    for (size_t v : used) lo = glm::min(lo, file_positions[v]), hi = glm::max(hi, file_positions[v]);
    const glm::dvec3 size = hi - lo;
    const double extent = std::max(size.x, std::max(size.y, size.z));
    PENUMBRA_CHECK(extent > 0.0, where, "all ", used.size(), " used vertices coincide");
    const glm::dvec3 anchor(0.5 * (lo.x + hi.x), lo.y, 0.5 * (lo.z + hi.z));
    Mesh mesh;
    mesh.name = stem;
    mesh.positions.reserve(used.size());
    for (size_t v : used) mesh.positions.emplace_back((file_positions[v] - anchor) / extent);
    mesh.indices.reserve(triangles.size() * 3);
    for (const auto& triangle : triangles)
        for (uint32_t v : triangle) mesh.indices.push_back(remap[v]);
    // A file whose every triangle has no area (collinear corners, to within float rounding in the
    // unit box) casts nothing and shows nothing:
    // refused rather than rendered as an empty scene.
    {
        size_t flat = 0;
        for (const auto& triangle : triangles) {
            // Normalised first: 1e-300-sized coordinates would underflow the cross product.
            const glm::dvec3 a = (file_positions[triangle[0]] - anchor) / extent;
            const glm::dvec3 b = (file_positions[triangle[1]] - anchor) / extent;
            const glm::dvec3 c = (file_positions[triangle[2]] - anchor) / extent;
            const glm::dvec3 n = glm::cross(b - a, c - a);
            flat += glm::length(n) <= 1e-14;  // below float's ulp^2 in the unit box: no area once rounded
        }
        PENUMBRA_CHECK(flat < triangles.size(), where, "every one of the ", triangles.size(),
                       " triangles has zero area (collinear corners): nothing to render");
    }

    // File normals are usable only as one normal per position: per-corner normals (hard edges)
    // would need split vertices, which would break index-based adjacency.
    bool use_file_normals = normal_count > 0;
    std::vector<int> vertex_normal(mesh.positions.size(), -1);
    for (size_t t = 0; t < triangles.size() && use_file_normals; ++t) {
        for (size_t k = 0; k < 3 && use_file_normals; ++k) {
            const int n = triangle_normals[t][k];
            if (n < 0 || static_cast<size_t>(n) >= normal_count) {
                use_file_normals = false;
                break;
            }
            int& chosen = vertex_normal[mesh.indices[3 * t + k]];
            if (chosen < 0) {
                chosen = n;
            } else if (chosen != n) {
                for (size_t c = 0; c < 3; ++c)  // different index, same vector is still one normal
                    use_file_normals = use_file_normals && attrib.normals[3 * size_t(chosen) + c] ==
                                                               attrib.normals[3 * size_t(n) + c];
            }
        }
    }
    if (use_file_normals) {
        mesh.normals.resize(mesh.positions.size());
        for (size_t v = 0; v < mesh.positions.size() && use_file_normals; ++v) {
            const size_t n = static_cast<size_t>(vertex_normal[v]);
            const glm::vec3 normal(static_cast<float>(attrib.normals[3 * n]), static_cast<float>(attrib.normals[3 * n + 1]),
                                   static_cast<float>(attrib.normals[3 * n + 2]));
            const float length = glm::length(normal);
            use_file_normals = std::isfinite(length) && length > 0.0f;
            if (use_file_normals) mesh.normals[v] = normal / length;
        }
    }

    // Topology, orientation and normals from the normalised positions: a uniform scale and a
    // translation change none of them, and the raw floats may have lost the shape.
    mesh.closed = isClosed(mesh);
    if (mesh.closed && signedVolume(mesh) < 0.0) {
        for (size_t t = 0; t < mesh.indices.size(); t += 3) std::swap(mesh.indices[t + 1], mesh.indices[t + 2]);
    }
    if (use_file_normals) {
        // Files whose normals oppose their winding (on the whole) get them turned around, so
        // shading agrees with the front faces that culling and shadow casting use.
        double agreement = 0.0;
        for (size_t t = 0; t < mesh.indices.size(); t += 3) {
            const glm::vec3 a = mesh.positions[mesh.indices[t]], b = mesh.positions[mesh.indices[t + 1]],
                            c = mesh.positions[mesh.indices[t + 2]];
            const glm::vec3 sum = mesh.normals[mesh.indices[t]] + mesh.normals[mesh.indices[t + 1]] +
                                  mesh.normals[mesh.indices[t + 2]];
            agreement += static_cast<double>(glm::dot(glm::cross(b - a, c - a), sum));
        }
        if (agreement < 0.0)
            for (glm::vec3& normal : mesh.normals) normal = -normal;
    } else {
        computeSmoothNormals(mesh);
    }

    float ground_y = 0.0f;
    if (!options.normalize) {
        for (size_t k = 0; k < used.size(); ++k) mesh.positions[k] = glm::vec3(file_positions[used[k]]);
        const Bounds box = mesh.bounds();
        const glm::vec3 float_size = box.size();
        const float float_extent = std::max(float_size.x, std::max(float_size.y, float_size.z));
        PENUMBRA_CHECK(std::isfinite(float_extent), where, "coordinates too large (extent overflows float)");
        PENUMBRA_CHECK(float_extent > 0.0f, where, "all ", used.size(), " used vertices coincide in float (extent ",
                       extent, " at distance ", std::max(glm::length(lo), glm::length(hi)),
                       " from the origin); normalize = true keeps the shape");
        ground_y = box.min.y;
    }

    std::string prefix = where;
    if (report.short_faces > 0)
        report.warnings.push_back(prefix + std::to_string(report.short_faces) + " faces of fewer than 3 corners dropped");
    if (report.repeated_index_triangles > 0)
        report.warnings.push_back(prefix + std::to_string(report.repeated_index_triangles) +
                                  " triangles repeating a vertex index dropped");
    if (report.duplicate_triangles > 0)
        report.warnings.push_back(prefix + std::to_string(report.duplicate_triangles) + " duplicate triangles " +
                                  (options.remove_duplicate_triangles
                                       ? "removed (they repeat an earlier triangle's positions and block the same light)"
                                       : "kept (remove_duplicate_triangles = false): each is tested again"));
    Scene scene = sceneFromMesh(std::move(mesh), ground_y, options.ground);
    progress(1.0);
    return scene;
}

}  // namespace detail

inline Scene loadObj(const std::string& path, const ObjOptions& options, ObjReport& report) {
    const std::string where = "penumbra::scene::loadObj('" + path + "'): ";
    std::ifstream file(path, std::ios::binary);
    PENUMBRA_CHECK(file.is_open(), where, "cannot open file");
    std::ostringstream text;
    text << file.rdbuf();
    PENUMBRA_CHECK(!file.bad(), where, "cannot read file");
    return detail::loadObjText(text.str(), where, detail::fileStem(path), options, report);
}

inline Scene loadObj(const std::string& path, const ObjOptions& options) {
    ObjReport report;
    return loadObj(path, options, report);
}

inline Scene parseObj(const std::string& text, const std::string& name, const ObjOptions& options,
                      ObjReport& report) {
    return detail::loadObjText(text, "penumbra::scene::parseObj('" + name + "'): ", detail::fileStem(name), options,
                               report);
}

inline Scene parseObj(const std::string& text, const std::string& name, const ObjOptions& options) {
    ObjReport report;
    return parseObj(text, name, options, report);
}

inline Scene load(const std::string& spec) {
    static const std::string kBuiltinPrefix = "builtin:";
    if (spec.compare(0, kBuiltinPrefix.size(), kBuiltinPrefix) == 0)
        return builtin(spec.substr(kBuiltinPrefix.size()));
    return loadObj(spec);
}

}  // namespace penumbra::scene

#endif
