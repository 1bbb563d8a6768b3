#include "mjcf_document.hpp"

#include <sys/stat.h>

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <strings.h>
#include <set>

#include "featherdrive/io/error.hpp"
#include "featherdrive/io/files.hpp"
#include "featherdrive/io/mjcf.hpp"

namespace featherdrive::mjcf_document {
namespace {

namespace fs = std::filesystem;

// Attributes whose values are names, paths or text, never numbers ("nan" is a valid name).
const std::set<std::string>& text_attributes() {
  static const std::set<std::string> names = {
      "name",      "class",     "childclass", "model",     "prefix",     "file",
      "fileright", "fileleft",  "fileup",     "filedown",  "filefront",  "fileback",
      "meshdir",   "texturedir", "joint",     "joint1",    "joint2",     "body",
      "body1",     "body2",     "site",       "site1",     "site2",      "geom",
      "geom1",     "geom2",     "tendon",     "tendon1",   "tendon2",    "actuator",
      "mesh",      "material",  "texture",    "hfield",    "skin",       "target",
      "objname",   "refname",   "jointinparent", "cranksite", "slidersite", "content_type"};
  return names;
}

// MuJoCo's mjuu_getfiledir: the name up to its last '/' or '\', "" without one.
std::string folder_of(const std::string& name) {
  const size_t last = name.find_last_of("/\\");
  return last == std::string::npos ? "" : name.substr(0, last + 1);
}

// MuJoCo's mjuu_isabspath.
bool absolute(const std::string& path) {
  return !path.empty() && (path[0] == '/' || path[0] == '\\' ||
                           path.find(":/") != std::string::npos ||
                           path.find(":\\") != std::string::npos);
}

// The characters an XML attribute value stands for (the five entities and character
// references, as TinyXML2 reads them); anything else is kept as written.
std::string decoded(const std::string& raw) {
  std::string out;
  for (size_t i = 0; i < raw.size(); ++i) {
    const size_t end = raw[i] == '&' ? raw.find(';', i) : std::string::npos;
    if (end == std::string::npos || end - i > 12) {
      out += raw[i];
      continue;
    }
    const std::string entity = raw.substr(i + 1, end - i - 1);
    long code = -1;
    if (entity == "lt") code = '<';
    else if (entity == "gt") code = '>';
    else if (entity == "amp") code = '&';
    else if (entity == "quot") code = '"';
    else if (entity == "apos") code = '\'';
    else if (entity.size() > 1 && entity[0] == '#') {
      const bool hex = entity[1] == 'x' || entity[1] == 'X';
      char* stop = nullptr;
      code = std::strtol(entity.c_str() + (hex ? 2 : 1), &stop, hex ? 16 : 10);
      if (*stop != '\0') code = -1;
    }
    if (code <= 0 || code > 0x7f) {  // only ASCII matters to the checks here
      out += raw[i];
      continue;
    }
    out += static_cast<char>(code);
    i = end;
  }
  return out;
}

struct Attribute {
  std::string name, value;
};

// A referenced asset file: where it is named and under which folder MuJoCo looks for it.
struct Asset {
  std::string element, attribute, value, where;
  bool texture = false;
};

struct Checker {
  const mjVFS* vfs = nullptr;
  std::string shown;   // the document's name in messages
  std::string folder;  // MuJoCo's modelfiledir
  std::vector<std::string> included;
  std::vector<fs::path> files;
  std::vector<Asset> assets;
  std::string meshdir, texturedir;
  bool strippath = false;
  size_t bytes = 0;
  long keys = 0;
  std::string first_key_where;

  [[noreturn]] void fail(const std::string& where, const std::string& what) const {
    throw InputError(shown + ": " + where + what);
  }

  // mj_findFileVFS(vfs, name). MuJoCo's own mju_error (MujocoError here, through its parser's
  // frames when it reads an include) takes a name whose part after the last '/' or '\' is empty
  // or mjMAXVFSNAME long: refused first, `what` naming the element and attribute.
  int find_in_vfs(const std::string& name, const std::string& where,
                  const std::string& what) const {
    const size_t slash = name.find_last_of("/\\");
    const size_t length = name.size() - (slash == std::string::npos ? 0 : slash + 1);
    if (length == 0) fail(where, what + " = '" + name + "': names no file");
    if (length >= mjMAXVFSNAME)
      fail(where, what + " = '" + name + "': the file name is longer than " +
                      std::to_string(mjMAXVFSNAME - 1) + " characters (MuJoCo's bound)");
    return mj_findFileVFS(vfs, name.c_str());
  }

  // The text of `name` as MuJoCo reads it: from the VFS when it holds the name, else the file.
  std::string read(const std::string& name, const char* what, const std::string& where) {
    if (vfs) {
      const int id = find_in_vfs(name, where, "file");
      if (id >= 0)
        return std::string(static_cast<const char*>(vfs->filedata[id]),
                           static_cast<size_t>(vfs->filesize[id]));
    }
    std::string text;
    try {
      text = read_input_file(name, what);
    } catch (const InputError& e) {
      if (where.empty()) throw;
      fail(where, e.what());
    }
    files.emplace_back(name);
    return text;
  }

  // One file's elements; `depth` is the nesting of its root element in the whole document.
  void scan(const std::string& text, const std::string& file, int depth, bool top) {
    bytes += text.size();
    if (bytes > kMaxInputBytes)
      fail(file + ": ", "the document with its includes is larger than " +
                            std::to_string(kMaxInputBytes >> 20) + " MiB");
    const std::string prefix = top ? "" : file + ", ";
    const size_t n = text.size();
    int line = 1;
    bool root_seen = false;
    std::vector<std::string> open;  // this file's open elements
    auto count_lines = [&](size_t from, size_t to) {
      for (size_t k = from; k < to && k < n; ++k) line += text[k] == '\n';
    };
    for (size_t i = 0; i < n;) {
      if (text[i] != '<') {
        line += text[i] == '\n';
        ++i;
        continue;
      }
      const char* end_marker = text.compare(i, 4, "<!--") == 0        ? "-->"
                               : text.compare(i, 9, "<![CDATA[") == 0 ? "]]>"
                               : text.compare(i, 2, "<!") == 0        ? ">"
                                                                      : nullptr;
      if (end_marker) {
        const size_t at = text.find(end_marker, i);
        const size_t stop = at == std::string::npos ? n : at + std::strlen(end_marker);
        count_lines(i, stop);
        i = stop;
        continue;
      }
      // A tag: up to the first '>' outside quoted values.
      const int tag_line = line;
      size_t j = i + 1;
      char quote = 0;
      for (; j < n && (quote || text[j] != '>'); ++j) {
        if (quote) {
          if (text[j] == quote) quote = 0;
        } else if (text[j] == '"' || text[j] == '\'') {
          quote = text[j];
        }
      }
      count_lines(i, j);
      const std::string tag = text.substr(i + 1, j - i - 1);
      i = j + 1;
      if (tag.empty() || tag[0] == '?') continue;
      if (tag[0] == '/') {
        if (!open.empty()) open.pop_back();
        continue;
      }
      const bool empty = tag.back() == '/';
      size_t k = 0;
      while (k < tag.size() && !std::isspace(static_cast<unsigned char>(tag[k])) && tag[k] != '/')
        ++k;
      const std::string element = tag.substr(0, k);
      const std::string where = prefix + "line " + std::to_string(tag_line) + ": ";
      const int level = depth + static_cast<int>(open.size());
      if (!root_seen) {
        root_seen = true;
        if (top && element != "mujoco")
          fail(where, "the root element is <" + element + ">, not <mujoco> (an MJCF file)");
      }
      if (level > kMaxMjcfDepth)
        fail(where, "elements nested deeper than " + std::to_string(kMaxMjcfDepth) +
                        " with includes followed (the bound)");
      const std::vector<Attribute> attributes = parse_attributes(tag, k);
      element_checks(element, attributes, where, level);
      if (!empty) open.push_back(element);
    }
    if (!root_seen) fail(prefix, "no root element (an MJCF file is <mujoco>...</mujoco>)");
  }

  static std::vector<Attribute> parse_attributes(const std::string& tag, size_t k) {
    std::vector<Attribute> out;
    const size_t n = tag.size();
    auto space = [&] {
      while (k < n && std::isspace(static_cast<unsigned char>(tag[k]))) ++k;
    };
    for (;;) {
      space();
      const size_t start = k;
      while (k < n && tag[k] != '=' && !std::isspace(static_cast<unsigned char>(tag[k])) &&
             tag[k] != '/')
        ++k;
      if (k == start) return out;
      Attribute a{tag.substr(start, k - start), ""};
      space();
      if (k >= n || tag[k] != '=') return out;  // TinyXML2 reports the syntax
      ++k;
      space();
      if (k >= n || (tag[k] != '"' && tag[k] != '\'')) return out;
      const size_t close = tag.find(tag[k], k + 1);
      if (close == std::string::npos) return out;
      a.value = decoded(tag.substr(k + 1, close - k - 1));
      k = close + 1;
      out.push_back(std::move(a));
    }
  }

  void element_checks(const std::string& element, const std::vector<Attribute>& attributes,
                      const std::string& where, int level) {
    for (const Attribute& a : attributes) {
      if (text_attributes().count(a.name) || (element == "text" && a.name == "data")) continue;
      check_finite(element, a, where);
    }
    auto value = [&](const char* name) -> const std::string* {
      for (const Attribute& a : attributes)
        if (a.name == name) return &a.value;
      return nullptr;
    };
    if (element == "include") {
      if (const std::string* file = value("file")) include(*file, where, level);
    } else if (element == "compiler") {
      if (const std::string* v = value("meshdir")) meshdir = *v;
      if (const std::string* v = value("texturedir")) texturedir = *v;
      if (const std::string* v = value("strippath")) strippath = *v == "true";
    } else if (element == "mesh" || element == "skin" || element == "hfield") {
      if (const std::string* v = value("file")) assets.push_back({element, "file", *v, where});
    } else if (element == "texture") {
      for (const char* name :
           {"file", "fileright", "fileleft", "fileup", "filedown", "filefront", "fileback"})
        if (const std::string* v = value(name)) assets.push_back({element, name, *v, where, true});
    } else if (element == "size") {
      for (const Attribute& a : attributes) check_size(a, where);
    } else if (element == "key") {
      if (keys++ == 0) first_key_where = where;
    }
  }

  // Each whitespace-separated token that reads in full as a number must be finite.
  void check_finite(const std::string& element, const Attribute& a, const std::string& where) {
    const std::string& v = a.value;
    for (size_t i = 0; i < v.size();) {
      while (i < v.size() && std::isspace(static_cast<unsigned char>(v[i]))) ++i;
      size_t j = i;
      while (j < v.size() && !std::isspace(static_cast<unsigned char>(v[j]))) ++j;
      if (j > i) {
        const std::string token = v.substr(i, j - i);
        char* stop = nullptr;
        const double x = std::strtod(token.c_str(), &stop);
        if (*stop == '\0' && !std::isfinite(x))
          fail(where, "<" + element + "> " + a.name + " = \"" + v + "\": " +
                          (std::isnan(x) ? "not a number" : "not finite") +
                          " (MuJoCo would put its default in its place)");
      }
      i = j;
    }
  }

  void check_size(const Attribute& a, const std::string& where) {
    long bound = 0;
    const char* why = "";
    if (a.name == "nkey") {
      bound = kMaxMjcfKeyframes;
      why = "MuJoCo's compiler takes time quadratic in keyframes";
    } else if (a.name.rfind("nuser_", 0) == 0) {
      bound = kMaxMjcfUserValues;
      why = "MuJoCo allocates that many numbers per element";
    } else if (a.name == "nuserdata") {
      bound = kMaxMjcfUserData;
      why = "MuJoCo allocates them in every mjData";
    } else if (a.name == "nstack") {
      bound = kMaxMjcfStack;
      why = "MuJoCo allocates them in every mjData";
    } else if (a.name == "njmax" || a.name == "nconmax") {
      bound = kMaxMjcfConstraints;
      why = "MuJoCo allocates per constraint a row as long as the model's dofs";
    } else {
      return;
    }
    char* stop = nullptr;
    errno = 0;
    const double x = std::strtod(a.value.c_str(), &stop);
    if (stop != a.value.c_str() && x > static_cast<double>(bound))
      fail(where, "<size> " + a.name + " = \"" + a.value + "\": above the bound " +
                      std::to_string(bound) + " (" + why + ")");
  }

  void include(const std::string& file, const std::string& where, int level) {
    const std::string name = folder + file;  // MuJoCo: the main file's folder, always
    for (const std::string& seen : included)
      if (strcasecmp(seen.c_str(), name.c_str()) == 0) return;  // MuJoCo refuses the repeat
    if (static_cast<int>(included.size()) > kMaxMjcfIncludes)
      fail(where, "more than " + std::to_string(kMaxMjcfIncludes) + " included files (the bound)");
    included.push_back(name);
    const std::string text = read(name, "the included file", where + "<include> ");
    // The included root's children take the place of <include>, at its depth.
    scan(text, name, level - 1, false);
  }

  // Every asset file MuJoCo will open: regular and not too large, or absent from the disk (MuJoCo
  // reports that one).
  void check_assets() {
    for (const Asset& a : assets) {
      std::string file = a.value;
      if (strippath) file = file.substr(file.find_last_of("/\\") + 1);
      std::string dir = a.texture ? texturedir : meshdir;
      if (!dir.empty() && dir.back() != '/' && dir.back() != '\\') dir += '/';
      const std::string path =
          absolute(file) ? file : absolute(dir) ? dir + file : folder + dir + file;
      if (vfs && find_in_vfs(path, a.where, "<" + a.element + "> " + a.attribute) >= 0) continue;
      struct stat st {};
      if (::stat(path.c_str(), &st) != 0) continue;
      const std::string what = "<" + a.element + "> " + a.attribute + " '" + path + "' ";
      if (S_ISDIR(st.st_mode)) fail(a.where, what + "is a directory");
      if (!S_ISREG(st.st_mode)) fail(a.where, what + "is not a regular file");
      if (static_cast<std::uintmax_t>(st.st_size) > kMaxInputBytes)
        fail(a.where, what + "is larger than " + std::to_string(kMaxInputBytes >> 20) + " MiB");
      files.emplace_back(path);
    }
  }
};

}  // namespace

std::vector<fs::path> check(const std::string& filename, const mjVFS* vfs,
                            const std::string& shown) {
  Checker c;
  c.vfs = vfs;
  c.shown = shown;
  c.folder = folder_of(filename);
  c.included.push_back(filename);
  const std::string text = c.read(filename, "the MJCF file", "");
  c.scan(text, shown, 1, true);
  if (c.keys > kMaxMjcfKeyframes)
    c.fail(c.first_key_where, std::to_string(c.keys) + " <key> elements: above the bound " +
                                  std::to_string(kMaxMjcfKeyframes) +
                                  " (MuJoCo's compiler takes time quadratic in keyframes)");
  c.check_assets();
  return std::move(c.files);
}

}  // namespace featherdrive::mjcf_document
