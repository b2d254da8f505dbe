#include "scene/ply_loader.h"

#include <algorithm>
#include <bit>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <sstream>
#include <vector>

#include <memory>

#include <libdeflate.h>

#include "raster/huge_pages.h"
#include "scene/input_error.h"
#include "scene/text_parsing.h"
#include "scene/file_names.h"

namespace cuberille::scene {
namespace {

enum class Encoding { Ascii, BinaryLittleEndian, BinaryBigEndian };
enum class Type { Int8, UInt8, Int16, UInt16, Int32, UInt32, Float32, Float64 };

struct Property {
    std::string name;
    Type type = Type::Float32;
    bool isList = false;
    Type countType = Type::UInt8;
};

struct Element {
    std::string name;
    size_t count = 0;
    std::vector<Property> properties;
};

struct Header {
    Encoding encoding = Encoding::Ascii;
    std::vector<Element> elements;
    size_t bodyOffset = 0;  // first byte after end_header's line
};

[[noreturn]] void fail(const std::string& file, const std::string& where, const std::string& problem) {
    throw InputError(file + ": " + where + ": " + problem);
}

// A value from the file as a person would write it: integers without decimals.
std::string formatValue(double v) {
    char buffer[32];
    std::snprintf(buffer, sizeof buffer, "%.17g", v);
    return buffer;
}

int sizeOf(Type t) {
    switch (t) {
        case Type::Int8: case Type::UInt8: return 1;
        case Type::Int16: case Type::UInt16: return 2;
        case Type::Int32: case Type::UInt32: case Type::Float32: return 4;
        case Type::Float64: return 8;
    }
    return 0;
}

bool parseType(std::string_view name, Type& out) {
    static const std::pair<std::string_view, Type> kTypes[] = {
        {"char", Type::Int8},     {"int8", Type::Int8},       {"uchar", Type::UInt8},
        {"uint8", Type::UInt8},   {"short", Type::Int16},     {"int16", Type::Int16},
        {"ushort", Type::UInt16}, {"uint16", Type::UInt16},   {"int", Type::Int32},
        {"int32", Type::Int32},   {"uint", Type::UInt32},     {"uint32", Type::UInt32},
        {"float", Type::Float32}, {"float32", Type::Float32}, {"double", Type::Float64},
        {"float64", Type::Float64}};
    for (auto [n, t] : kTypes)
        if (n == name) {
            out = t;
            return true;
        }
    return false;
}

Header parseHeader(std::string_view bytes, const std::string& file) {
    Header h;
    size_t pos = 0, lineNumber = 0;
    bool sawFormat = false;
    while (true) {
        const size_t end = bytes.find('\n', pos);
        if (end == std::string_view::npos) fail(file, "header", "no end_header line");
        ++lineNumber;
        const std::string_view line = bytes.substr(pos, end - pos);
        pos = end + 1;
        const auto w = splitWords(line);
        const std::string where = "header line " + std::to_string(lineNumber);
        if (lineNumber == 1) {
            if (w.size() != 1 || w[0] != "ply") fail(file, where, "not a PLY file (no 'ply' magic)");
            continue;
        }
        if (w.empty() || w[0] == "comment" || w[0] == "obj_info") continue;
        if (w[0] == "format") {
            if (w.size() != 3) fail(file, where, "malformed format line");
            if (w[1] == "ascii") h.encoding = Encoding::Ascii;
            else if (w[1] == "binary_little_endian") h.encoding = Encoding::BinaryLittleEndian;
            else if (w[1] == "binary_big_endian") h.encoding = Encoding::BinaryBigEndian;
            else fail(file, where, "unknown format '" + std::string(w[1]) + "'");
            sawFormat = true;
        } else if (w[0] == "element") {
            size_t count = 0;
            if (w.size() != 3 || std::from_chars(w[2].data(), w[2].data() + w[2].size(), count).ec != std::errc())
                fail(file, where, "malformed element line");
            h.elements.push_back({std::string(w[1]), count, {}});
        } else if (w[0] == "property") {
            if (h.elements.empty()) fail(file, where, "property before any element");
            Property p;
            if (w.size() == 5 && w[1] == "list") {
                p.isList = true;
                if (!parseType(w[2], p.countType) || !parseType(w[3], p.type))
                    fail(file, where, "unknown list types");
                if (p.countType == Type::Float32 || p.countType == Type::Float64)
                    fail(file, where, "list count must be an integer type");
                p.name = w[4];
            } else if (w.size() == 3) {
                if (!parseType(w[1], p.type)) fail(file, where, "unknown type '" + std::string(w[1]) + "'");
                p.name = w[2];
            } else {
                fail(file, where, "malformed property line");
            }
            h.elements.back().properties.push_back(p);
        } else if (w[0] == "end_header") {
            break;
        } else {
            fail(file, where, "unexpected '" + std::string(w[0]) + "'");
        }
    }
    if (!sawFormat) fail(file, "header", "no format line");
    h.bodyOffset = pos;
    return h;
}

// A binary value at p as a double (every PLY type converts to one exactly), its bytes swapped
// when the file's endianness differs from the machine's.
double decodeBinary(const char* p, Type t, bool swap) {
    const int n = sizeOf(t);
    uint64_t raw = 0;
    std::memcpy(&raw, p, size_t(n));
    if (swap) {
        if (n == 2) raw = __builtin_bswap16(uint16_t(raw));
        if (n == 4) raw = __builtin_bswap32(uint32_t(raw));
        if (n == 8) raw = __builtin_bswap64(raw);
    }
    unsigned char b[8];
    std::memcpy(b, &raw, 8);
    switch (t) {
        case Type::Int8: return double(int8_t(b[0]));
        case Type::UInt8: return double(b[0]);
        case Type::Int16: { int16_t v; std::memcpy(&v, b, 2); return v; }
        case Type::UInt16: { uint16_t v; std::memcpy(&v, b, 2); return v; }
        case Type::Int32: { int32_t v; std::memcpy(&v, b, 4); return v; }
        case Type::UInt32: { uint32_t v; std::memcpy(&v, b, 4); return v; }
        case Type::Float32: { float v; std::memcpy(&v, b, 4); return v; }
        case Type::Float64: { double v; std::memcpy(&v, b, 8); return v; }
    }
    return 0;
}

// Where in the body a value is read: an element and an instance, formatted only for a message
// (a scan has millions of instances; building a string for each cost more than reading them).
struct Place {
    const std::string& element;
    size_t index;
    std::string str() const { return element + " " + std::to_string(index); }
};

// Reads the values of one element instance, one property at a time, in either encoding.
class BodyReader {
public:
    BodyReader(std::string_view bytes, size_t offset, Encoding encoding, const std::string& file)
        : bytes_(bytes), pos_(offset), encoding_(encoding), file_(file) {}

    size_t offset() const { return pos_; }
    size_t remaining() const { return bytes_.size() - pos_; }

    double read(Type t, const Place& where) {
        if (encoding_ == Encoding::Ascii) return readAscii(where);
        const int n = sizeOf(t);
        if (remaining() < size_t(n)) fail(file_, where.str(), "unexpected end of file at byte " + std::to_string(pos_));
        const double v = decodeBinary(bytes_.data() + pos_, t, swapsBytes());
        pos_ += size_t(n);
        return v;
    }

    bool swapsBytes() const {
        return encoding_ != Encoding::Ascii &&
               (encoding_ == Encoding::BinaryBigEndian) == (std::endian::native == std::endian::little);
    }
    const char* position() const { return bytes_.data() + pos_; }
    void skip(size_t bytes) { pos_ += bytes; }

    // ASCII instances end at a newline; checks nothing is left over on the line.
    void endInstance(const Place& where) {
        if (encoding_ != Encoding::Ascii) return;
        while (pos_ < bytes_.size() && isBlank(bytes_[pos_])) ++pos_;
        if (pos_ < bytes_.size() && bytes_[pos_] != '\n') fail(file_, where.str(), "more values than the header declares");
        if (pos_ < bytes_.size()) ++pos_;
    }

private:
    double readAscii(const Place& where) {
        while (pos_ < bytes_.size() && isBlank(bytes_[pos_])) ++pos_;
        if (pos_ >= bytes_.size() || bytes_[pos_] == '\n')
            fail(file_, where.str(), pos_ >= bytes_.size() ? "unexpected end of file" : "fewer values than the header declares");
        double v = 0;
        const char* first = bytes_.data() + pos_;
        const char* last = bytes_.data() + bytes_.size();
        auto [end, ec] = std::from_chars(first, last, v);
        if (ec != std::errc()) fail(file_, where.str(), "not a number at byte " + std::to_string(pos_));
        pos_ += size_t(end - first);
        return v;
    }

    std::string_view bytes_;
    size_t pos_;
    Encoding encoding_;
    const std::string& file_;
};

// Smallest number of bytes one instance of the element can occupy (binary), or characters
// (ASCII: at least one digit and a separator per value).
size_t minimumInstanceBytes(const Element& e, Encoding encoding) {
    size_t n = 0;
    for (const Property& p : e.properties)
        n += encoding == Encoding::Ascii ? 2 : size_t(sizeOf(p.isList ? p.countType : p.type));
    return std::max<size_t>(n, 1);
}

// A `tristrips` list restarts its strip at -1 (the convention of the Stanford and Cyberware
// scans' writers); kRestartIndex marks the place in the gathered list.
constexpr double kStripRestart = -1.0;
constexpr uint32_t kRestartIndex = UINT32_MAX;

// One index of a face or strip list into the gathered polygon: a vertex, or in a strip a
// restart. False for anything else, which the caller reports (or leaves to the general reader).
bool gatherIndex(double v, bool strips, size_t vertexCount, std::vector<uint32_t>& polygon) {
    if (strips && v == kStripRestart) polygon.push_back(kRestartIndex);
    else if (v >= 0 && v < double(vertexCount) && v == std::floor(v)) polygon.push_back(uint32_t(v));
    else return false;
    return true;
}

void appendTriangle(std::vector<uint32_t>& indices, uint32_t a, uint32_t b, uint32_t c) {
    // Three push_backs: an insert of an initializer list costs a memmove a triangle, a fifth of
    // reading a scan's faces.
    indices.push_back(a);
    indices.push_back(b);
    indices.push_back(c);
}

// A polygon of n vertices as the fan (v0, v[k-1], v[k]), its winding kept.
void appendFan(const std::vector<uint32_t>& polygon, std::vector<uint32_t>& indices) {
    for (size_t k = 2; k < polygon.size(); ++k) appendTriangle(indices, polygon[0], polygon[k - 1], polygon[k]);
}

// Strips separated by restarts. Triangle i of a strip is (s[i], s[i+1], s[i+2]), with its first
// two vertices swapped when i is odd so that every triangle keeps the strip's first winding; i
// counts from each restart. Triangles that repeat a vertex are the joins a writer uses to stitch
// strips together: they have no area and are dropped.
void appendStrips(const std::vector<uint32_t>& strips, std::vector<uint32_t>& indices) {
    size_t stripStart = 0;
    for (size_t k = 0; k < strips.size(); ++k) {
        if (strips[k] == kRestartIndex) {
            stripStart = k + 1;
            continue;
        }
        const size_t i = k - stripStart;  // this vertex's place in its strip
        if (i < 2) continue;
        uint32_t a = strips[k - 2], b = strips[k - 1];
        const uint32_t c = strips[k];
        if ((i - 2) % 2 == 1) std::swap(a, b);
        if (a == b || b == c || a == c) continue;
        appendTriangle(indices, a, b, c);
    }
}

int findProperty(const Element& e, std::initializer_list<std::string_view> names) {
    for (size_t i = 0; i < e.properties.size(); ++i)
        for (std::string_view n : names)
            if (e.properties[i].name == n) return int(i);
    return -1;
}

// The property indices parsePly reads from a vertex element (-1: absent).
struct VertexLayout {
    int x, y, z, nx, ny, nz, r, g, b;
    bool hasNormals, hasColors;
};

void storeVertex(const VertexLayout& l, const Element& e, const double* values, size_t i, Mesh& mesh) {
    mesh.positions[i] = glm::vec3(values[l.x], values[l.y], values[l.z]);
    if (l.hasNormals) mesh.normals[i] = glm::vec3(values[l.nx], values[l.ny], values[l.nz]);
    if (l.hasColors) {
        const float scale = e.properties[size_t(l.r)].type == Type::UInt8 ? 1.0f / 255.0f : 1.0f;
        mesh.colors[i] = glm::vec3(srgbToLinear(float(values[l.r]) * scale), srgbToLinear(float(values[l.g]) * scale),
                                   srgbToLinear(float(values[l.b]) * scale));
    }
}

bool finitePosition(const VertexLayout& l, const double* values) {
    return std::isfinite(float(values[l.x])) && std::isfinite(float(values[l.y])) && std::isfinite(float(values[l.z]));
}

// Binary fast paths for the layouts scans use: whole instances decoded from the bytes without a
// call per value or a check per byte. Each takes instances from the reader's position while they
// are well formed and returns how many it took; the general reader resumes at the first it did
// not take, and reports its problem with its place.

// An element of scalar properties only (a vertex element): fixed-size instances.
size_t readFixedInstances(const Element& e, const VertexLayout& l, BodyReader& reader, Mesh& mesh) {
    size_t instanceBytes = 0;
    for (const Property& p : e.properties) {
        if (p.isList) return 0;
        instanceBytes += size_t(sizeOf(p.type));
    }
    const size_t available = std::min(e.count, reader.remaining() / std::max<size_t>(instanceBytes, 1));
    const bool swap = reader.swapsBytes();
    std::vector<double> values(e.properties.size());
    size_t taken = 0;
    const bool allNativeFloats = !swap && std::all_of(e.properties.begin(), e.properties.end(),
                                                      [](const Property& p) { return p.type == Type::Float32; });
    for (; taken < available; ++taken) {
        const char* p = reader.position();
        if (allNativeFloats) {  // the common scan layout: floats in the machine's order, no conversion a value
            for (size_t k = 0; k < values.size(); ++k, p += 4) {
                float v;
                std::memcpy(&v, p, 4);
                values[k] = v;
            }
        } else {
            for (size_t k = 0; k < e.properties.size(); ++k) {
                values[k] = decodeBinary(p, e.properties[k].type, swap);
                p += sizeOf(e.properties[k].type);
            }
        }
        if (!finitePosition(l, values.data())) break;
        storeVertex(l, e, values.data(), taken, mesh);
        reader.skip(instanceBytes);
    }
    return taken;
}

// An element whose one property is the vertex index list (a face or tristrips element).
size_t readIndexLists(const Element& e, bool strips, size_t vertexCount, BodyReader& reader, Mesh& mesh) {
    if (e.properties.size() != 1 || !e.properties[0].isList) return 0;
    const Property& list = e.properties[0];
    const size_t countBytes = size_t(sizeOf(list.countType)), indexBytes = size_t(sizeOf(list.type));
    const bool swap = reader.swapsBytes();
    const bool signedIndices = list.type == Type::Int32;
    const bool raw32 = !swap && (signedIndices || list.type == Type::UInt32);
    // Most scans' faces are triangles of uchar counts and int indices: room for that many.
    if (!strips)
        raster::reserveAdvised(mesh.indices, mesh.indices.size() + 3 * std::min(e.count, reader.remaining() / (countBytes + 3 * indexBytes)));
    std::vector<uint32_t> polygon;
    size_t taken = 0;
    for (; taken < e.count; ++taken) {
        if (reader.remaining() < countBytes) break;
        const double count = list.countType == Type::UInt8 ? double(uint8_t(*reader.position()))
                                                            : decodeBinary(reader.position(), list.countType, swap);
        if (!(count >= 0) || count > double((reader.remaining() - countBytes) / indexBytes)) break;
        const char* p = reader.position() + countBytes;
        polygon.clear();
        bool valid = true;
        if (raw32) {  // 32-bit indices in the machine's order: no conversion a value
            for (size_t k = 0; k < size_t(count) && valid; ++k, p += 4) {
                uint32_t v;
                std::memcpy(&v, p, 4);
                if (strips && signedIndices && v == uint32_t(-1)) polygon.push_back(kRestartIndex);
                else if (v < vertexCount && !(signedIndices && v > uint32_t(INT32_MAX))) polygon.push_back(v);
                else valid = false;
            }
        } else {
            for (size_t k = 0; k < size_t(count) && valid; ++k, p += indexBytes)
                valid = gatherIndex(decodeBinary(p, list.type, swap), strips, vertexCount, polygon);
        }
        if (!valid) break;
        if (strips) appendStrips(polygon, mesh.indices);
        else appendFan(polygon, mesh.indices);
        reader.skip(countBytes + size_t(count) * indexBytes);
    }
    return taken;
}

}  // namespace

Mesh parsePly(std::string_view bytes, const std::string& file) {
    const Header h = parseHeader(bytes, file);
    Mesh mesh;
    BodyReader reader(bytes, h.bodyOffset, h.encoding, file);
    size_t vertexCount = 0;
    bool sawVertices = false, hasNormals = false;
    for (const Element& e : h.elements) {
        if (e.count > reader.remaining() / minimumInstanceBytes(e, h.encoding))
            fail(file, "element '" + e.name + "'", std::to_string(e.count) + " instances cannot fit in the " +
                                                       std::to_string(reader.remaining()) + " bytes left");
        const bool isVertex = e.name == "vertex", isFace = e.name == "face", isStrips = e.name == "tristrips";
        const int x = findProperty(e, {"x"}), y = findProperty(e, {"y"}), z = findProperty(e, {"z"});
        const int nx = findProperty(e, {"nx"}), ny = findProperty(e, {"ny"}), nz = findProperty(e, {"nz"});
        const int r = findProperty(e, {"red", "r"}), g = findProperty(e, {"green", "g"}), b = findProperty(e, {"blue", "b"});
        const int list = findProperty(e, {"vertex_indices", "vertex_index"});
        const bool hasColors = isVertex && r >= 0 && g >= 0 && b >= 0;
        if (isVertex) {
            if (x < 0 || y < 0 || z < 0) fail(file, "element 'vertex'", "no x, y and z properties");
            if (sawVertices) fail(file, "element 'vertex'", "a second vertex element");
            sawVertices = true;
            vertexCount = e.count;
            hasNormals = nx >= 0 && ny >= 0 && nz >= 0;
            raster::resizeAdvised(mesh.positions, e.count);
            if (hasNormals) raster::resizeAdvised(mesh.normals, e.count);
            if (hasColors) raster::resizeAdvised(mesh.colors, e.count);
        }
        if ((isFace || isStrips) && list < 0) fail(file, "element '" + e.name + "'", "no vertex_indices list");
        if ((isFace || isStrips) && !sawVertices) fail(file, "element '" + e.name + "'", e.name + " before vertices");
        const VertexLayout layout{x, y, z, nx, ny, nz, r, g, b, hasNormals, hasColors};
        size_t first = 0;  // instances a fast path took
        if (h.encoding != Encoding::Ascii && isVertex) first = readFixedInstances(e, layout, reader, mesh);
        if (h.encoding != Encoding::Ascii && (isFace || isStrips)) first = readIndexLists(e, isStrips, vertexCount, reader, mesh);
        std::vector<double> values(e.properties.size());  // this instance's scalar properties
        std::vector<uint32_t> polygon;
        for (size_t i = first; i < e.count; ++i) {
            const Place where{e.name, i};
            for (size_t p = 0; p < e.properties.size(); ++p) {
                const Property& prop = e.properties[p];
                if (!prop.isList) {
                    values[p] = reader.read(prop.type, where);
                    continue;
                }
                const double countValue = reader.read(prop.countType, where);
                // A list can be long (one `tristrips` instance often holds a whole scan), but not
                // longer than the bytes left can hold, checked before anything is gathered.
                // (ASCII: a digit and a separator a value, the last one's separator optional.)
                const size_t fitting = h.encoding == Encoding::Ascii ? (reader.remaining() + 1) / 2
                                                                     : reader.remaining() / size_t(sizeOf(prop.type));
                if (!(countValue >= 0) || countValue > double(fitting))
                    fail(file, where.str(), "list length " + formatValue(countValue) + " cannot fit in the " +
                                          std::to_string(reader.remaining()) + " bytes left");
                const size_t count = size_t(countValue);
                const bool isIndices = (isFace || isStrips) && int(p) == list;
                if (isIndices) polygon.clear();
                for (size_t k = 0; k < count; ++k) {
                    const double v = reader.read(prop.type, where);
                    if (isIndices && !gatherIndex(v, isStrips, vertexCount, polygon))
                        fail(file, where.str(), "vertex index " + formatValue(v) + " is out of range (" +
                                              std::to_string(vertexCount) + " vertices)");
                }
                if (isIndices && isFace) appendFan(polygon, mesh.indices);
                if (isIndices && isStrips) appendStrips(polygon, mesh.indices);
            }
            reader.endInstance(where);
            if (!isVertex) continue;
            if (!finitePosition(layout, values.data())) fail(file, where.str(), "position is not finite");
            storeVertex(layout, e, values.data(), i, mesh);
        }
    }
    if (!sawVertices) fail(file, "header", "no vertex element");
    if (!hasNormals) computeVertexNormals(mesh);
    return mesh;
}

namespace {

bool startsGzipMember(const std::string& bytes, size_t at) {
    return bytes.size() - at >= 2 && uint8_t(bytes[at]) == 0x1f && uint8_t(bytes[at + 1]) == 0x8b;
}

/// A gzip file's bytes inflated in memory by libdeflate, about twice zlib's streaming speed
/// (the Stanford dragon's 31 MB PLY: 82 ms through gzread). As gzip and zlib read them:
/// members one after another, anything after the last member that is not one ignored, and a
/// file that is not gzip at all taken as it is. A member's output buffer starts at the size its
/// trailer gives for the file's last member (exact for the usual one-member file; the trailer
/// holds the size mod 2^32) and doubles while it is too small.
constexpr size_t kMostDeflateExpansion = 1032;

std::string inflateGzip(const std::string& name, const std::string& compressed) {
    if (!startsGzipMember(compressed, 0)) return compressed;
    std::unique_ptr<libdeflate_decompressor, void (*)(libdeflate_decompressor*)> inflater(
        libdeflate_alloc_decompressor(), libdeflate_free_decompressor);
    if (!inflater) throw std::bad_alloc();
    uint32_t lastMemberSize = 0;
    if (compressed.size() >= 4) std::memcpy(&lastMemberSize, compressed.data() + compressed.size() - 4, 4);  // little-endian
    std::string out;
    size_t at = 0;
    while (at < compressed.size() && (at == 0 || startsGzipMember(compressed, at))) {
        // DEFLATE expands at most 1032:1 (a 258-byte match in under two bits), so a member
        // wanting more room than that is damaged: libdeflate cannot tell a cut stream from a
        // short buffer, and would otherwise be fed ever larger ones. The same bound keeps a
        // trailer that is not a size (trailing bytes, damage) from sizing the first buffer.
        const size_t mostPossible = (compressed.size() - at) * kMostDeflateExpansion + (size_t(1) << 16);
        size_t room = std::min(std::max<size_t>(lastMemberSize, size_t(1) << 16), mostPossible);
        for (;;) {
            const size_t before = out.size();
            out.resize(before + room);
            size_t used = 0, produced = 0;
            const libdeflate_result result = libdeflate_gzip_decompress_ex(
                inflater.get(), compressed.data() + at, compressed.size() - at, out.data() + before, room, &used, &produced);
            if (result == LIBDEFLATE_INSUFFICIENT_SPACE && room < mostPossible) {
                out.resize(before);
                room = std::min(room * 2, mostPossible);
                continue;
            }
            if (result != LIBDEFLATE_SUCCESS) throw InputError(name + ": corrupt gzip data (at compressed byte " + std::to_string(at) + ")");
            out.resize(before + produced);
            at += used;
            break;
        }
    }
    return out;
}

std::string readPlainFileBytes(const std::filesystem::path& path);

}  // namespace

std::string readFileBytes(const std::filesystem::path& path) {
    if (lowerExtension(path) == ".gz") return inflateGzip(path.string(), readPlainFileBytes(path));
    return readPlainFileBytes(path);
}

namespace {

std::string readPlainFileBytes(const std::filesystem::path& path) {
    const std::string name = path.string();
    // A folder opens as a stream on Linux and reports a nonsense size (found by fuzz_obj: an
    // `mtllib` name that is empty up to a NUL names the OBJ's folder).
    std::error_code ec;
    if (std::filesystem::is_directory(path, ec)) throw InputError(name + ": is a folder, not a file");
    std::ifstream in(path, std::ios::binary | std::ios::ate);
    if (!in) throw InputError(name + ": cannot open file");
    // A regular file: one read into a string of its size (a stream copy through a stringbuf cost
    // as much again as the read). Anything else (a pipe) is streamed.
    if (std::filesystem::is_regular_file(path, ec)) {
        const std::streamoff size = in.tellg();
        if (size < 0) throw InputError(name + ": cannot read file");
        std::string bytes(size_t(size), '\0');
        in.seekg(0);
        if (!in.read(bytes.data(), size)) throw InputError(name + ": cannot read file");
        return bytes;
    }
    in.seekg(0);
    std::ostringstream buffer;
    buffer << in.rdbuf();
    return buffer.str();
}

}  // namespace

Mesh loadPly(const std::filesystem::path& path) { return parsePly(readFileBytes(path), path.string()); }

}  // namespace cuberille::scene
