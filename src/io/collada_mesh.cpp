#include "collada_mesh.hpp"

#include <tinyxml.h>

#include <charconv>
#include <cmath>
#include <map>
#include <numbers>
#include <stdexcept>

#include "xml_text.hpp"

namespace featherdrive::collada {
namespace {

using Affine = Eigen::Affine3d;

[[noreturn]] void fail(const std::string& what) {
  throw std::runtime_error(what);
}

std::string text_of(const TiXmlElement* e) {
  const char* t = e->GetText();
  return t ? t : "";
}

std::string attribute(const TiXmlElement* e, const char* name) {
  const char* a = e->Attribute(name);
  return a ? a : "";
}

// "<float_array id='positions'> (line N)": how messages name an element.
std::string label(const TiXmlElement* e) {
  const std::string id = attribute(e, "id");
  return "<" + std::string(e->Value()) + (id.empty() ? "" : " id='" + id + "'") + "> (line " +
         std::to_string(e->Row()) + ")";
}

// The whitespace-separated numbers of an element's text (xs:double: a leading '+' allowed),
// each finite.
std::vector<double> numbers(const TiXmlElement* e) {
  const std::string t = text_of(e);
  std::vector<double> out;
  const char* p = t.data();
  const char* end = p + t.size();
  auto space = [](char c) { return c == ' ' || c == '\t' || c == '\n' || c == '\r'; };
  while (true) {
    while (p < end && space(*p)) ++p;
    if (p == end) break;
    const char* start = p;
    while (p < end && !space(*p)) ++p;
    const std::string word(start, p);
    double v = 0.0;
    const char* first = word.data() + (word[0] == '+' ? 1 : 0);
    const auto [at, ec] = std::from_chars(first, word.data() + word.size(), v);
    if (ec != std::errc() || at != word.data() + word.size() || !std::isfinite(v))
      fail(label(e) + ": value " + std::to_string(out.size()) + " = '" + word +
           "' is not a finite number");
    out.push_back(v);
  }
  return out;
}

// The element `url` ("#id") names among `ids`; other files' elements are not read.
const TiXmlElement* find(const std::map<std::string, const TiXmlElement*>& ids,
                         const TiXmlElement* from, const char* attribute_name) {
  const std::string url = attribute(from, attribute_name);
  if (url.empty() || url[0] != '#')
    fail(label(from) + ": " + attribute_name + " = '" + url +
         "': only references to this file's elements (#id) are read");
  const auto it = ids.find(url.substr(1));
  if (it == ids.end()) fail(label(from) + ": " + attribute_name + " = '" + url + "': no such id");
  return it->second;
}

// Instances multiply a file's vertices (a node instantiating another twice, 30 deep, is 2^30
// copies): placed vertices and node visits are bounded (a robot's collision meshes hold
// thousands; MuJoCo's inline text of 2e6 vertices is about 150 MB).
constexpr size_t kMaxPlacedVertices = 2'000'000;
constexpr long kMaxNodeVisits = 1'000'000;

struct Reader {
  std::map<std::string, const TiXmlElement*> ids;              // every element with an id
  std::map<const TiXmlElement*, std::vector<Vec3>> positions;  // per <geometry>, read once
  std::vector<Vec3> out;
  long visits = 0;

  void index(const TiXmlElement* e) {
    for (; e; e = e->NextSiblingElement()) {
      if (const char* id = e->Attribute("id")) ids.emplace(id, e);
      index(e->FirstChildElement());  // depth bounded by check_nesting
    }
  }

  void add_geometry(const TiXmlElement* geometry, const Affine& placed) {
    auto [it, added] = positions.try_emplace(geometry);
    if (added) it->second = read_positions(geometry);
    if (out.size() + it->second.size() > kMaxPlacedVertices)
      fail("the scene places more than " + std::to_string(kMaxPlacedVertices) + " vertices");
    for (const Vec3& p : it->second) out.push_back(placed * p);
  }

  // The positions of a <geometry>'s <mesh>: <vertices><input semantic="POSITION" source="#s">,
  // <source id="s"><float_array> read through its <technique_common><accessor> (offset, stride,
  // count: the first three values of each element are x, y, z).
  std::vector<Vec3> read_positions(const TiXmlElement* geometry) {
    std::vector<Vec3> read;
    const TiXmlElement* mesh = geometry->FirstChildElement("mesh");
    if (!mesh) return read;  // <convex_mesh>, <spline>, <brep>: nothing a hull reads here
    const TiXmlElement* vertices = mesh->FirstChildElement("vertices");
    if (!vertices) fail(label(geometry) + ": its <mesh> has no <vertices>");
    const TiXmlElement* position = nullptr;
    for (const TiXmlElement* in = vertices->FirstChildElement("input"); in && !position;
         in = in->NextSiblingElement("input"))
      if (attribute(in, "semantic") == "POSITION") position = in;
    if (!position) fail(label(vertices) + ": no <input semantic='POSITION'>");
    const TiXmlElement* source = find(ids, position, "source");
    const TiXmlElement* common = source->FirstChildElement("technique_common");
    const TiXmlElement* accessor = common ? common->FirstChildElement("accessor") : nullptr;
    if (std::string(source->Value()) != "source" || !accessor)
      fail(label(source) + ": not a <source> with a <technique_common><accessor>");
    const TiXmlElement* array = find(ids, accessor, "source");
    if (std::string(array->Value()) != "float_array")
      fail(label(accessor) + ": source names " + label(array) + ", not a <float_array>");
    const std::vector<double> values = numbers(array);
    if (attribute(array, "count") != std::to_string(values.size()))
      fail(label(array) + ": count = '" + attribute(array, "count") + "' but it holds " +
           std::to_string(values.size()) + " numbers");
    auto whole = [&](const char* name, long fallback) {
      const std::string s = attribute(accessor, name);
      long v = fallback;
      if (!s.empty()) {
        const auto [at, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
        if (ec != std::errc() || at != s.data() + s.size() || v < 0)
          fail(label(accessor) + ": " + name + " = '" + s + "': must be a whole number >= 0");
      }
      return v;
    };
    const long count = whole("count", -1), stride = whole("stride", 1), offset = whole("offset", 0);
    if (count < 0) fail(label(accessor) + ": no count");
    if (stride < 3)
      fail(label(accessor) + ": stride = " + std::to_string(stride) +
           ": positions need 3 values (x, y, z)");
    const auto size = static_cast<long>(values.size());
    if (count > 0 && (offset > size - 3 || count - 1 > (size - offset - 3) / stride))
      fail(label(accessor) + ": count " + std::to_string(count) + ", stride " +
           std::to_string(stride) + ", offset " + std::to_string(offset) + " read beyond the " +
           std::to_string(size) + " numbers of " + label(array));
    for (long k = 0; k < count; ++k) {
      const double* v = values.data() + offset + k * stride;
      read.emplace_back(v[0], v[1], v[2]);
    }
    return read;
  }

  // A node's transform: its <matrix>, <translate>, <rotate> and <scale> children composed in
  // document order (COLLADA 1.4, "Transform elements"), applied to its geometry and child nodes.
  void add_node(const TiXmlElement* node, Affine placed, int depth) {
    if (depth > kMaxColladaDepth)
      fail(label(node) + ": nodes instantiated deeper than " + std::to_string(kMaxColladaDepth));
    if (++visits > kMaxNodeVisits)
      fail("the scene instantiates more than " + std::to_string(kMaxNodeVisits) + " nodes");
    for (const TiXmlElement* e = node->FirstChildElement(); e; e = e->NextSiblingElement()) {
      const std::string kind = e->Value();
      auto values = [&](size_t n) {
        std::vector<double> v = numbers(e);
        if (v.size() != n)
          fail(label(e) + ": " + std::to_string(v.size()) + " numbers, expected " +
               std::to_string(n));
        return v;
      };
      if (kind == "matrix") {  // row-major 4x4
        const std::vector<double> v = values(16);
        Eigen::Matrix4d m;
        for (int r = 0; r < 4; ++r)
          for (int c = 0; c < 4; ++c) m(r, c) = v[static_cast<size_t>(4 * r + c)];
        if (m.row(3) != Eigen::RowVector4d(0, 0, 0, 1))
          fail(label(e) + ": its last row is not 0 0 0 1 (a projection)");
        placed = placed * Affine(m);
      } else if (kind == "translate") {
        const std::vector<double> v = values(3);
        placed.translate(Vec3(v[0], v[1], v[2]));
      } else if (kind == "rotate") {  // axis x y z, angle in degrees
        const std::vector<double> v = values(4);
        const Vec3 axis(v[0], v[1], v[2]);
        if (!(axis.norm() > 0.0)) fail(label(e) + ": the axis is zero");
        placed.rotate(Eigen::AngleAxisd(v[3] * std::numbers::pi / 180.0, axis.normalized()));
      } else if (kind == "scale") {
        const std::vector<double> v = values(3);
        placed.scale(Vec3(v[0], v[1], v[2]));
      } else if (kind == "lookat" || kind == "skew") {
        fail(label(e) + ": <" + kind + "> transforms are not read");
      } else if (kind == "instance_geometry") {
        const TiXmlElement* g = find(ids, e, "url");
        if (std::string(g->Value()) != "geometry") fail(label(e) + ": url names " + label(g));
        add_geometry(g, placed);
      } else if (kind == "node") {
        add_node(e, placed, depth + 1);
      } else if (kind == "instance_node") {
        const TiXmlElement* n = find(ids, e, "url");
        if (std::string(n->Value()) != "node") fail(label(e) + ": url names " + label(n));
        add_node(n, placed, depth + 1);
      }
    }
  }
};

}  // namespace

std::vector<Vec3> vertices(const std::string& xml) {
  xml_text::check_utf8(xml);
  xml_text::check_nesting(xml, kMaxColladaDepth);
  TiXmlDocument doc;
  doc.Parse(xml.c_str());
  if (doc.Error() && doc.ErrorId() == TiXmlBase::TIXML_ERROR_DOCUMENT_EMPTY)
    fail("not XML: it holds no element");
  if (doc.Error())
    fail("line " + std::to_string(doc.ErrorRow()) + ", column " + std::to_string(doc.ErrorCol()) +
         ": malformed XML: " + doc.ErrorDesc());
  const TiXmlElement* root = doc.RootElement();
  if (!root || std::string(root->Value()) != "COLLADA")
    fail(std::string("the root element is <") + (root ? root->Value() : "") +
         ">, expected <COLLADA>");
  double metre = 1.0;  // <asset><unit meter="0.01"/>: one unit is 0.01 m
  const TiXmlElement* asset = root->FirstChildElement("asset");
  if (const TiXmlElement* unit = asset ? asset->FirstChildElement("unit") : nullptr) {
    const std::string s = attribute(unit, "meter");
    const auto [at, ec] = std::from_chars(s.data(), s.data() + s.size(), metre);
    if (!s.empty() &&
        (ec != std::errc() || at != s.data() + s.size() || !std::isfinite(metre) || metre <= 0.0))
      fail("<asset><unit meter> = '" + s + "': must be a finite number > 0");
    if (s.empty()) metre = 1.0;
  }
  // <up_axis> is checked and not applied: ROS's mesh readers (rviz, MoveIt's geometric_shapes,
  // Gazebo) skip the rotation assimp puts on the root for it, and files marked Y_UP with z-up
  // data (DART's WAM) rely on that (docs/math/contact.md, G3).
  if (const TiXmlElement* up = asset ? asset->FirstChildElement("up_axis") : nullptr) {
    std::string axis = text_of(up);
    axis.erase(0, axis.find_first_not_of(" \t\r\n"));
    axis.erase(axis.find_last_not_of(" \t\r\n") + 1);
    if (axis != "X_UP" && axis != "Y_UP" && axis != "Z_UP")
      fail("<asset><up_axis> = '" + axis + "': must be X_UP, Y_UP or Z_UP");
  }
  Reader reader;
  reader.index(root);
  // The scene: <scene><instance_visual_scene url>, else the first <visual_scene>.
  const TiXmlElement* scene = nullptr;
  const TiXmlElement* which = root->FirstChildElement("scene");
  if (const TiXmlElement* i = which ? which->FirstChildElement("instance_visual_scene") : nullptr) {
    scene = find(reader.ids, i, "url");
    if (std::string(scene->Value()) != "visual_scene")
      fail(label(i) + ": url names " + label(scene));
  }
  const TiXmlElement* library = root->FirstChildElement("library_visual_scenes");
  if (!scene && library) scene = library->FirstChildElement("visual_scene");
  const Affine metres(Eigen::Scaling(metre));
  if (scene) {
    reader.add_node(scene, metres, 0);
  } else {  // no scene: every geometry where it is
    for (const TiXmlElement* l = root->FirstChildElement("library_geometries"); l;
         l = l->NextSiblingElement("library_geometries"))
      for (const TiXmlElement* g = l->FirstChildElement("geometry"); g;
           g = g->NextSiblingElement("geometry"))
        reader.add_geometry(g, metres);
  }
  if (reader.out.empty())
    fail(scene ? "its visual scene places no <geometry> with a <mesh> of vertices"
               : "no <library_geometries><geometry><mesh> with vertices");
  return reader.out;
}

}  // namespace featherdrive::collada
