// PLY (Turk 1994: the Stanford polygon format), ASCII and binary of either byte order, read by our
// own parser: the header's elements and properties in any order and of any type, vertex positions,
// normals, texture coordinates and colours, faces as index lists (polygons split by ear clipping).
// Every count is checked against the file's size before anything is allocated, and every index
// before it is used; docs/meshes.md ("PLY") lists what is read and what is refused.
#include <algorithm>
#include <array>
#include <bit>
#include <charconv>
#include <cmath>
#include <cstring>
#include <fstream>
#include <iterator>
#include <limits>
#include <string_view>

#include "image/image.h"
#include "scene/mesh_import.h"
#include "scene/scene_limits.h"
#include "scene/triangulate.h"
#include "util/error.h"

namespace vkray {

namespace {

using glm::dvec3;

enum class Encoding { Ascii, BinaryLittleEndian, BinaryBigEndian };

enum class Type : std::uint8_t { Int8, UInt8, Int16, UInt16, Int32, UInt32, Float32, Float64 };

struct TypeName {
  std::string_view name;
  Type type;
};

// The specification's names and the sized ones later writers use.
constexpr TypeName kTypeNames[] = {
    {"char", Type::Int8},   {"uchar", Type::UInt8},   {"short", Type::Int16},     {"ushort", Type::UInt16},
    {"int", Type::Int32},   {"uint", Type::UInt32},   {"float", Type::Float32},   {"double", Type::Float64},
    {"int8", Type::Int8},   {"uint8", Type::UInt8},   {"int16", Type::Int16},     {"uint16", Type::UInt16},
    {"int32", Type::Int32}, {"uint32", Type::UInt32}, {"float32", Type::Float32}, {"float64", Type::Float64},
};

std::size_t sizeOf(Type t) {
  switch (t) {
  case Type::Int8:
  case Type::UInt8:
    return 1;
  case Type::Int16:
  case Type::UInt16:
    return 2;
  case Type::Int32:
  case Type::UInt32:
  case Type::Float32:
    return 4;
  case Type::Float64:
    return 8;
  }
  return 0;
}

bool isInteger(Type t) {
  return t != Type::Float32 && t != Type::Float64;
}

std::string_view nameOf(Type t) {
  for (const TypeName& n : kTypeNames) {
    if (n.type == t) return n.name;
  }
  return "?";
}

// What a vertex property is to vkray; the rest are read past.
enum Role : std::int8_t { kSkip = -1, kX, kY, kZ, kNx, kNy, kNz, kU, kV, kRed, kGreen, kBlue, kRoleCount };

struct Property {
  std::string name;
  Type type = Type::Float32; // the value's, or a list's items'
  bool list = false;
  Type countType = Type::UInt8; // a list's length
  std::size_t line = 0;         // in the header
  Role role = kSkip;
  bool faceIndices = false; // the face element's vertex_indices
};

struct Element {
  std::string name;
  std::uint64_t count = 0;
  std::vector<Property> properties;
  std::size_t line = 0;
};

struct Header {
  Encoding encoding = Encoding::Ascii;
  std::vector<Element> elements;
  std::size_t bodyOffset = 0; // the first byte after end_header's line
  std::size_t bodyLine = 0;   // the body's first line number (ASCII)
};

std::vector<std::string_view> tokens(std::string_view line) {
  std::vector<std::string_view> out;
  std::size_t i = 0;
  while (true) {
    i = line.find_first_not_of(" \t\r\f\v", i);
    if (i == std::string_view::npos) break;
    std::size_t j = line.find_first_of(" \t\r\f\v", i);
    if (j == std::string_view::npos) j = line.size();
    out.push_back(line.substr(i, j - i));
    i = j;
  }
  return out;
}

std::string shown(std::string_view s) {
  constexpr std::size_t kShown = 40;
  std::string out(s.substr(0, kShown));
  for (char& c : out) {
    if (static_cast<unsigned char>(c) < 0x20 || static_cast<unsigned char>(c) >= 0x7F) c = '?';
  }
  return "'" + out + (s.size() > kShown ? "...'" : "'");
}

class HeaderParser {
public:
  HeaderParser(std::string_view text, const std::string& where) : text_(text), where_(where) {}

  Header parse() {
    std::string_view first = nextLine();
    if (tokens(first) != std::vector<std::string_view>{"ply"}) fail("not a PLY file (it does not begin with 'ply')");
    bool haveFormat = false;
    while (true) {
      if (pos_ >= text_.size()) fail("the header has no end_header line");
      std::string_view raw = nextLine();
      std::vector<std::string_view> t = tokens(raw);
      if (t.empty()) continue;
      const std::string_view key = t[0];
      if (key == "comment" || key == "obj_info") continue;
      if (key == "end_header") {
        if (t.size() != 1) failLine("end_header has something after it");
        break;
      }
      if (key == "format") {
        if (haveFormat) failLine("a second format line");
        if (t.size() != 3) failLine("format needs an encoding and a version ('format ascii 1.0')");
        if (t[1] == "ascii") {
          header_.encoding = Encoding::Ascii;
        } else if (t[1] == "binary_little_endian") {
          header_.encoding = Encoding::BinaryLittleEndian;
        } else if (t[1] == "binary_big_endian") {
          header_.encoding = Encoding::BinaryBigEndian;
        } else {
          failLine("unsupported format " + shown(t[1]) +
                   " (vkray reads ascii, binary_little_endian and binary_big_endian)");
        }
        if (t[2] != "1.0") failLine("unsupported PLY version " + shown(t[2]) + " (vkray reads 1.0)");
        haveFormat = true;
      } else if (key == "element") {
        if (t.size() != 3) failLine("element needs a name and a count ('element vertex 8')");
        Element e;
        e.name = name(t[1]);
        e.line = line_;
        auto [end, ec] = std::from_chars(t[2].data(), t[2].data() + t[2].size(), e.count);
        if (ec != std::errc() || end != t[2].data() + t[2].size()) {
          failLine("element " + shown(t[1]) + ": the count " + shown(t[2]) + " is not a whole number");
        }
        for (const Element& other : header_.elements) {
          if (other.name == e.name) failLine("a second element " + shown(e.name));
        }
        header_.elements.push_back(std::move(e));
      } else if (key == "property") {
        if (header_.elements.empty()) failLine("a property before any element");
        Property p;
        p.line = line_;
        if (t.size() >= 2 && t[1] == "list") {
          if (t.size() != 5) failLine("a list property needs a count type, an item type and a name");
          p.list = true;
          p.countType = type(t[2]);
          p.type = type(t[3]);
          if (!isInteger(p.countType)) failLine("list " + shown(t[4]) + ": its count type must be an integer type");
          p.name = name(t[4]);
        } else {
          if (t.size() != 3) failLine("a property needs a type and a name ('property float x')");
          p.type = type(t[1]);
          p.name = name(t[2]);
        }
        Element& e = header_.elements.back();
        for (const Property& other : e.properties) {
          if (other.name == p.name) failLine("element " + shown(e.name) + " has a second property " + shown(p.name));
        }
        e.properties.push_back(std::move(p));
      } else if (header_.elements.empty()) {
        // Before the first element, a line that is no keyword is a stray comment: Blender 2.4's
        // exporter wrote its credit line without 'comment' (assimp's Wuson.ply). Among the elements
        // it stays an error, where it is more likely a misspelt property than a note.
        continue;
      } else {
        failLine(shown(key) + " is not a PLY header keyword (a comment line begins with 'comment')");
      }
    }
    if (!haveFormat) fail("the header has no format line");
    header_.bodyOffset = pos_;
    header_.bodyLine = line_ + 1;
    return header_;
  }

private:
  std::string_view nextLine() {
    std::size_t end = text_.find('\n', pos_);
    if (end == std::string_view::npos) end = text_.size();
    std::string_view line = text_.substr(pos_, end - pos_);
    pos_ = std::min(end + 1, text_.size());
    ++line_;
    return line;
  }

  // Element and property names appear in messages: printable ASCII only.
  std::string name(std::string_view token) const {
    for (char c : token) {
      if (static_cast<unsigned char>(c) <= 0x20 || static_cast<unsigned char>(c) >= 0x7F) {
        failLine("the name " + shown(token) + " is not printable ASCII");
      }
    }
    return std::string(token);
  }

  Type type(std::string_view name) const {
    for (const TypeName& n : kTypeNames) {
      if (n.name == name) return n.type;
    }
    failLine(shown(name) + " is not a PLY type (char, uchar, short, ushort, int, uint, float, double, or int8 ... "
                           "float64)");
  }

  [[noreturn]] void fail(const std::string& problem) const { throw InputError(where_, problem); }
  [[noreturn]] void failLine(const std::string& problem) const {
    throw InputError(where_, "header line " + std::to_string(line_) + ": " + problem);
  }

  std::string_view text_;
  const std::string& where_;
  std::size_t pos_ = 0;
  std::size_t line_ = 0;
  Header header_;
};

// The body, one element entry (a row) at a time. Both readers name the row in their messages.
class AsciiBody {
public:
  AsciiBody(std::string_view text, std::size_t firstLine, const std::string& where)
      : text_(text), line_(firstLine - 1), where_(where) {}

  // The next non-blank line is the row's.
  void beginRow(const Element& e, std::uint64_t index) {
    element_ = &e;
    index_ = index;
    while (true) {
      if (pos_ >= text_.size()) {
        fail("the file ends before " + e.name + " " + std::to_string(index) + " of " + std::to_string(e.count) +
                 " (truncated?)",
             false);
      }
      std::size_t end = text_.find('\n', pos_);
      if (end == std::string_view::npos) end = text_.size();
      row_ = text_.substr(pos_, end - pos_);
      pos_ = end + 1;
      ++line_;
      rowPos_ = 0;
      if (row_.find_first_not_of(" \t\r\f\v") != std::string_view::npos) return;
    }
  }

  double value(Type t, const Property& p) {
    rowPos_ = row_.find_first_not_of(" \t\r\f\v", rowPos_);
    if (rowPos_ == std::string_view::npos) {
      fail("too few values (the line ends before " + p.name + ")");
    }
    std::size_t end = row_.find_first_of(" \t\r\f\v", rowPos_);
    if (end == std::string_view::npos) end = row_.size();
    std::string_view token = row_.substr(rowPos_, end - rowPos_);
    rowPos_ = end;
    const char* first = token.data();
    const char* last = token.data() + token.size();
    if (first != last && *first == '+') ++first; // from_chars takes no '+'
    if (isInteger(t)) {
      long long v = 0;
      auto [stop, ec] = std::from_chars(first, last, v);
      if (ec != std::errc() || stop != last) {
        fail(p.name + ": " + shown(token) + " is not an integer (" + std::string(nameOf(t)) + ")");
      }
      auto [lo, hi] = range(t);
      if (v < lo || v > hi) fail(p.name + ": " + shown(token) + " is out of range for " + std::string(nameOf(t)));
      return static_cast<double>(v);
    }
    double v = 0.0;
    auto [stop, ec] = std::from_chars(first, last, v);
    if (ec == std::errc::result_out_of_range) fail(p.name + ": " + shown(token) + " is out of range");
    if (ec != std::errc() || stop != last) fail(p.name + ": " + shown(token) + " is not a number");
    // A float property holds what a binary file would: the value rounded to float.
    if (t == Type::Float32) {
      constexpr double kMax = std::numeric_limits<float>::max();
      if (std::isfinite(v) && std::abs(v) > kMax) return v > 0 ? INFINITY : -INFINITY;
      return static_cast<double>(static_cast<float>(v));
    }
    return v;
  }

  void endRow() {
    if (row_.find_first_not_of(" \t\r\f\v", rowPos_) != std::string_view::npos) {
      fail("more values than the header's " + std::to_string(element_->properties.size()) + " properties");
    }
  }

  void end() {
    while (pos_ < text_.size()) {
      std::size_t nl = std::min(text_.find('\n', pos_), text_.size());
      std::string_view line = text_.substr(pos_, nl - pos_);
      pos_ = nl + 1;
      ++line_;
      if (line.find_first_not_of(" \t\r\f\v") != std::string_view::npos) {
        throw InputError(where_,
                         "line " + std::to_string(line_) + ": more data after the last element the header declares");
      }
    }
  }

  // Element entries without properties take no room; the checks before reading refuse them.
  bool skipRows(const Element&, std::uint64_t) { return false; }

  [[noreturn]] void fail(const std::string& problem, bool inRow = true) const {
    std::string at = "line " + std::to_string(inRow ? line_ : line_ + 1) + ": ";
    if (inRow) at += element_->name + " " + std::to_string(index_) + ": ";
    throw InputError(where_, at + problem);
  }

private:
  static std::pair<long long, long long> range(Type t) {
    switch (t) {
    case Type::Int8:
      return {-128, 127};
    case Type::UInt8:
      return {0, 255};
    case Type::Int16:
      return {-32768, 32767};
    case Type::UInt16:
      return {0, 65535};
    case Type::Int32:
      return {-2147483648LL, 2147483647LL};
    default:
      return {0, 4294967295LL};
    }
  }

  std::string_view text_;
  std::size_t pos_ = 0;
  std::size_t line_;
  std::string_view row_;
  std::size_t rowPos_ = 0;
  const Element* element_ = nullptr;
  std::uint64_t index_ = 0;
  const std::string& where_;
};

class BinaryBody {
public:
  BinaryBody(std::string_view bytes, std::size_t offset, bool bigEndian, const std::string& where)
      : bytes_(bytes), base_(offset), swap_(bigEndian != (std::endian::native == std::endian::big)), where_(where) {}

  void beginRow(const Element& e, std::uint64_t index) {
    element_ = &e;
    index_ = index;
  }

  double value(Type t, const Property&) {
    std::size_t n = sizeOf(t);
    if (bytes_.size() - pos_ < n) {
      fail("the file ends inside it (truncated?)");
    }
    unsigned char b[8];
    std::memcpy(b, bytes_.data() + pos_, n);
    pos_ += n;
    if (swap_) std::reverse(b, b + n);
    switch (t) {
    case Type::Int8:
      return static_cast<double>(static_cast<std::int8_t>(b[0]));
    case Type::UInt8:
      return static_cast<double>(b[0]);
    case Type::Int16:
      return static_cast<double>(load<std::int16_t>(b));
    case Type::UInt16:
      return static_cast<double>(load<std::uint16_t>(b));
    case Type::Int32:
      return static_cast<double>(load<std::int32_t>(b));
    case Type::UInt32:
      return static_cast<double>(load<std::uint32_t>(b));
    case Type::Float32:
      return static_cast<double>(load<float>(b));
    case Type::Float64:
      return load<double>(b);
    }
    return 0.0;
  }

  void endRow() {}

  void end() {
    if (pos_ != bytes_.size()) {
      throw InputError(where_,
                       std::to_string(bytes_.size() - pos_) + " bytes after the last element the header declares");
    }
  }

  // Rows of fixed size (no lists) are stepped over at once.
  bool skipRows(const Element& e, std::uint64_t count) {
    std::size_t row = 0;
    for (const Property& p : e.properties) {
      if (p.list) return false;
      row += sizeOf(p.type);
    }
    if (row != 0 && count > (bytes_.size() - pos_) / row) {
      element_ = &e;
      index_ = (bytes_.size() - pos_) / row;
      fail("the file ends inside it (truncated?)");
    }
    pos_ += static_cast<std::size_t>(count) * row;
    return true;
  }

  [[noreturn]] void fail(const std::string& problem) const {
    throw InputError(where_, element_->name + " " + std::to_string(index_) + " (byte " + std::to_string(base_ + pos_) +
                                 "): " + problem);
  }

private:
  template <class T> static T load(const unsigned char* b) {
    T v;
    std::memcpy(&v, b, sizeof v);
    return v;
  }

  std::string_view bytes_;
  std::size_t base_;
  std::size_t pos_ = 0;
  bool swap_;
  const Element* element_ = nullptr;
  std::uint64_t index_ = 0;
  const std::string& where_;
};

// The smallest number of bytes one entry of e can take: each value at least a digit and a
// separator in ASCII, its type's size in binary; a list at least its count, a face's indices at
// least three (fewer are refused).
std::size_t minRowBytes(const Element& e, Encoding encoding) {
  std::size_t n = 0;
  for (const Property& p : e.properties) {
    std::size_t items = p.faceIndices ? 3 : 0;
    n += encoding == Encoding::Ascii ? 2 * (1 + items) : sizeOf(p.list ? p.countType : p.type) + items * sizeOf(p.type);
  }
  return n;
}

struct ColorDecoder {
  std::array<float, 256> fromByte{};
  ColorDecoder() {
    for (int i = 0; i < 256; ++i) fromByte[static_cast<std::size_t>(i)] = srgbToLinear(static_cast<float>(i) / 255.0f);
  }
};

class PlyReader {
public:
  PlyReader(const MeshRequest& request, std::string_view text)
      : request_(request), where_(request.shownAs), text_(text) {}

  MeshData read() {
    header_ = HeaderParser(text_, where_).parse();
    findVertexAndFace();
    checkSizes();
    std::string_view body = text_.substr(header_.bodyOffset);
    if (header_.encoding == Encoding::Ascii) {
      AsciiBody in(body, header_.bodyLine, where_);
      readBody(in);
    } else {
      BinaryBody in(body, header_.bodyOffset, header_.encoding == Encoding::BinaryBigEndian, where_);
      readBody(in);
    }
    if (request_.importCamera) throw InputError(where_, "PLY files have no cameras (import_camera needs glTF)");
    if (request_.importLights) throw InputError(where_, "PLY files have no lights (import_lights needs glTF)");
    return std::move(data_);
  }

private:
  // The vertex and face elements, and what each of their properties is.
  void findVertexAndFace() {
    for (Element& e : header_.elements) {
      if (e.name == "vertex") vertex_ = &e;
      if (e.name == "face") face_ = &e;
    }
    if (!face_ || face_->count == 0) {
      if (!vertex_ || vertex_->count == 0) throw InputError(where_, "has no vertices and no faces");
      throw InputError(where_, "has no faces (a point cloud); vkray renders surfaces");
    }
    if (!vertex_) throw InputError(where_, "has faces but no vertex element");
    if (face_->count > kMaxPrimitives) {
      throw InputError(where_, "header line " + std::to_string(face_->line) + ": " + std::to_string(face_->count) +
                                   " faces are more than the scene limit of " + std::to_string(kMaxPrimitives) +
                                   " primitives");
    }
    if (vertex_->count >= MeshData::kNone) throw InputError(where_, "too many vertices for 32-bit indices");

    auto find = [&](std::string_view name) -> Property* {
      for (Property& p : vertex_->properties) {
        if (p.name == name) return &p;
      }
      return nullptr;
    };
    // A group of properties is used whole or not at all; the first of each group's spellings wins.
    auto group = [&](std::initializer_list<std::initializer_list<std::string_view>> spellings, Role first,
                     bool required) -> bool {
      for (auto names : spellings) {
        std::vector<Property*> found;
        for (std::string_view n : names) found.push_back(find(n));
        std::size_t present = static_cast<std::size_t>(
            std::count_if(found.begin(), found.end(), [](Property* p) { return p != nullptr; }));
        if (present == 0) continue;
        const Property* given = *std::find_if(found.begin(), found.end(), [](Property* p) { return p != nullptr; });
        std::size_t k = 0;
        for (std::string_view n : names) {
          if (!found[k]) {
            throw InputError(where_, "header line " + std::to_string(given->line) + ": vertex has " +
                                         shown(given->name) + " but no " + shown(n));
          }
          if (found[k]->list) {
            throw InputError(where_, "header line " + std::to_string(found[k]->line) + ": vertex property " + shown(n) +
                                         " is a list; it must be a number");
          }
          found[k]->role = static_cast<Role>(first + static_cast<int>(k));
          ++k;
        }
        return true;
      }
      if (required)
        throw InputError(where_, "header line " + std::to_string(vertex_->line) + ": vertex has no x, y, z");
      return false;
    };
    group({{"x", "y", "z"}}, kX, true);
    hasNormals_ = group({{"nx", "ny", "nz"}}, kNx, false);
    hasUvs_ = group({{"u", "v"}, {"s", "t"}, {"texture_u", "texture_v"}}, kU, false);
    hasColors_ = group({{"red", "green", "blue"}, {"diffuse_red", "diffuse_green", "diffuse_blue"}}, kRed, false);
    if (hasColors_) {
      for (const Property& p : vertex_->properties) {
        if (p.role >= kRed && p.role <= kBlue) colorProps_[static_cast<std::size_t>(p.role - kRed)] = &p;
        if (p.role >= kRed && p.role <= kBlue &&
            !(p.type == Type::UInt8 || p.type == Type::UInt16 || !isInteger(p.type))) {
          throw InputError(where_,
                           "header line " + std::to_string(p.line) + ": colour " + shown(p.name) + " is " +
                               std::string(nameOf(p.type)) +
                               "; vkray reads colours as uchar or ushort (0 .. max) or float or double (0 .. 1)");
        }
      }
    }

    Property* indices = nullptr;
    for (Property& p : face_->properties) {
      if (p.name != "vertex_indices" && p.name != "vertex_index") continue;
      if (indices) {
        throw InputError(where_,
                         "header line " + std::to_string(p.line) + ": face has both vertex_indices and vertex_index");
      }
      if (!p.list) {
        throw InputError(where_, "header line " + std::to_string(p.line) + ": face " + shown(p.name) +
                                     " is not a list ('property list uchar int vertex_indices')");
      }
      if (!isInteger(p.type)) {
        throw InputError(where_, "header line " + std::to_string(p.line) + ": face " + shown(p.name) + " has " +
                                     std::string(nameOf(p.type)) + " items; indices must be integers");
      }
      indices = &p;
    }
    if (!indices) {
      throw InputError(where_, "header line " + std::to_string(face_->line) +
                                   ": face has no vertex_indices (or vertex_index) list");
    }
    indices->faceIndices = true;
  }

  // Every element's entries must fit in the body before any room is made for them.
  void checkSizes() const {
    std::size_t room = text_.size() - header_.bodyOffset;
    if (header_.encoding == Encoding::Ascii) ++room; // the last line may lack its newline
    for (const Element& e : header_.elements) {
      if (e.count != 0 && e.properties.empty()) {
        throw InputError(where_, "header line " + std::to_string(e.line) + ": element " + shown(e.name) + " has " +
                                     std::to_string(e.count) + " entries but no properties");
      }
    }
    for (const Element& e : header_.elements) {
      if (e.count == 0) continue;
      std::size_t row = minRowBytes(e, header_.encoding);
      if (e.count > room / row) {
        throw InputError(where_, "header line " + std::to_string(e.line) + ": element " + shown(e.name) + " declares " +
                                     std::to_string(e.count) + (e.count == 1 ? " entry" : " entries") +
                                     ", more than the file's " + std::to_string(text_.size()) +
                                     " bytes can hold (truncated?)");
      }
      room -= static_cast<std::size_t>(e.count) * row;
    }
  }

  template <class Body> void readBody(Body& in) {
    const std::size_t vertexCount = static_cast<std::size_t>(vertex_->count);
    data_.positions.resize(vertexCount);
    if (hasNormals_) data_.normals.resize(vertexCount);
    if (hasUvs_) data_.texcoords.resize(vertexCount);
    if (hasColors_) data_.colors.resize(vertexCount);
    // Most meshes are triangles or quads: one triangle or two per face.
    data_.faces.reserve(static_cast<std::size_t>(face_->count));
    for (const Element& e : header_.elements) {
      if (&e == vertex_) {
        readVertices(in);
      } else if (&e == face_) {
        readFaces(in);
      } else if (!in.skipRows(e, e.count)) {
        std::array<double, kRoleCount> unused{};
        for (std::uint64_t i = 0; i < e.count; ++i) readRow(in, e, i, unused);
      }
    }
    in.end();
    if (hasNormals_) data_.faceNormals = data_.faces; // one normal per vertex
  }

  // One entry: scalars with a role land in `values`, the face's index list in indices_.
  template <class Body>
  void readRow(Body& in, const Element& e, std::uint64_t index, std::array<double, kRoleCount>& values) {
    in.beginRow(e, index);
    for (const Property& p : e.properties) {
      if (!p.list) {
        double v = in.value(p.type, p);
        if (p.role != kSkip) values[static_cast<std::size_t>(p.role)] = v;
        continue;
      }
      double count = in.value(p.countType, p);
      if (count < 0)
        in.fail(p.name + ": the list's length is negative (" + std::to_string(static_cast<long long>(count)) + ")");
      auto n = static_cast<std::size_t>(count);
      if (p.faceIndices) {
        indices_.clear();
        for (std::size_t k = 0; k < n; ++k) {
          double v = in.value(p.type, p);
          if (v < 0 || v >= static_cast<double>(vertex_->count)) {
            in.fail("vertex index " + std::to_string(static_cast<long long>(v)) + " is out of range (the file has " +
                    std::to_string(vertex_->count) + " vertices)");
          }
          indices_.push_back(static_cast<std::uint32_t>(v));
        }
      } else {
        for (std::size_t k = 0; k < n; ++k) in.value(p.type, p);
      }
    }
    in.endRow();
  }

  template <class Body> void readVertices(Body& in) {
    static const ColorDecoder decoder;
    std::array<double, kRoleCount> v{};
    for (std::uint64_t i = 0; i < vertex_->count; ++i) {
      readRow(in, *vertex_, i, v);
      const dvec3 p(v[kX], v[kY], v[kZ]);
      if (!(std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z))) in.fail("not finite (NaN or Inf)");
      data_.positions[i] = p;
      if (hasNormals_) data_.normals[i] = dvec3(v[kNx], v[kNy], v[kNz]);
      // Stored as the file's floats would round; v runs up in PLY (as in OBJ), down in glTF's texture
      // space, which the kernel samples in.
      if (hasUvs_) {
        data_.texcoords[i] = glm::dvec4(static_cast<float>(v[kU]), 1.0 - static_cast<float>(v[kV]), 0.0, 0.0);
      }
      if (hasColors_) {
        glm::vec3 c;
        for (int k = 0; k < 3; ++k) {
          const Property& prop = *colorProps_[static_cast<std::size_t>(k)];
          double x = v[static_cast<std::size_t>(kRed + k)];
          if (prop.type == Type::UInt8) {
            c[k] = decoder.fromByte[static_cast<std::size_t>(x)];
          } else if (prop.type == Type::UInt16) {
            c[k] = srgbToLinear(static_cast<float>(x / 65535.0));
          } else {
            if (!std::isfinite(x)) in.fail(prop.name + " is not finite (NaN or Inf)");
            c[k] = srgbToLinear(static_cast<float>(std::clamp(x, 0.0, 1.0)));
          }
        }
        data_.colors[i] = glm::dvec4(glm::dvec3(c), 1.0);
      }
    }
  }

  template <class Body> void readFaces(Body& in) {
    std::array<double, kRoleCount> unused{};
    for (std::uint64_t f = 0; f < face_->count; ++f) {
      readRow(in, *face_, f, unused);
      if (indices_.size() < 3) {
        in.fail("has " + std::to_string(indices_.size()) + " vertices (a face needs at least 3)");
      }
      if (indices_.size() == 3) {
        data_.faces.push_back({indices_[0], indices_[1], indices_[2]});
        continue;
      }
      corners_.clear();
      for (std::uint32_t i : indices_) corners_.push_back(data_.positions[i]);
      triangles_.clear();
      triangulatePolygon(corners_, triangles_);
      for (const Corners& t : triangles_) data_.faces.push_back({indices_[t[0]], indices_[t[1]], indices_[t[2]]});
    }
  }

  const MeshRequest& request_;
  const std::string& where_;
  std::string_view text_;
  Header header_;
  Element* vertex_ = nullptr;
  Element* face_ = nullptr;
  bool hasNormals_ = false;
  bool hasUvs_ = false;
  bool hasColors_ = false;
  std::array<const Property*, 3> colorProps_{};
  MeshData data_;
  std::vector<std::uint32_t> indices_;
  std::vector<dvec3> corners_;
  std::vector<Corners> triangles_;
};

} // namespace

MeshData readPly(const MeshRequest& request) {
  std::ifstream file(request.file, std::ios::binary);
  if (!file) throw InputError(request.shownAs, "cannot open for reading");
  std::string text((std::istreambuf_iterator<char>(file)), std::istreambuf_iterator<char>());
  return PlyReader(request, text).read();
}

} // namespace vkray
