#include "xml_text.hpp"

#include <cstring>
#include <sstream>
#include <stdexcept>

namespace featherdrive::xml_text {

// TinyXML 2.6 trusts a UTF-8 lead byte's length and steps over the text's terminating NUL when the
// sequence is cut short (fuzz_urdf found it reading past the buffer), and it stops silently at an
// embedded NUL. Refuse both before any XML reader sees the text.
void check_utf8(const std::string& text) {
  int line = 1, column = 1;
  for (std::size_t i = 0; i < text.size();) {
    const auto byte = static_cast<unsigned char>(text[i]);
    int length = 1;
    if (byte >= 0xF0 && byte <= 0xF4)
      length = 4;
    else if (byte >= 0xE0)
      length = byte <= 0xEF ? 3 : 0;
    else if (byte >= 0xC2)
      length = 2;
    else if (byte >= 0x80)
      length = 0;
    bool valid = length > 0 && i + length <= text.size() && byte != 0;
    for (int k = 1; valid && k < length; ++k)
      valid = (static_cast<unsigned char>(text[i + k]) & 0xC0) == 0x80;
    if (!valid) {
      std::ostringstream what;
      what << "line " << line << ", column " << column << " (byte " << i << "): ";
      if (byte == 0)
        what << "a NUL character";
      else
        what << "not valid UTF-8 (byte 0x" << std::hex << static_cast<int>(byte) << ")";
      throw std::runtime_error(what.str());
    }
    if (byte == '\n') {
      ++line;
      column = 1;
    } else {
      ++column;
    }
    i += length;
  }
}

// TinyXML (used by urdfdom too) parses and frees elements recursively, so a document nested
// tens of thousands deep overflows the stack. Count the nesting as TinyXML would read it: comments
// and CDATA end at "-->" and "]]>", "<!DOCTYPE ...>" and other "<!" at the first '>', "<?...?>" and
// tags at the first '>' outside quotes, "<a/>" opens nothing.
void check_nesting(const std::string& text, int max_depth) {
  int depth = 0, line = 1;
  const size_t n = text.size();
  // Moves i past the first `end` at or after it, counting lines; to the end if there is none.
  auto skip_to = [&](size_t& i, const char* end) {
    const size_t at = text.find(end, i);
    const size_t stop = at == std::string::npos ? n : at + std::strlen(end);
    for (; i < stop; ++i) line += text[i] == '\n';
  };
  // Moves i past the first '>' outside quoted values; true when the tag ends in "/>".
  auto skip_tag = [&](size_t& i) {
    char quote = 0, last = 0;
    for (; i < n; ++i) {
      const char c = text[i];
      line += c == '\n';
      if (quote) {
        if (c == quote) quote = 0;
      } else if (c == '"' || c == '\'') {
        quote = c;
      } else if (c == '>') {
        ++i;
        return last == '/';
      }
      if (!quote && c != ' ' && c != '\t' && c != '\n' && c != '\r') last = c;
    }
    return false;
  };
  for (size_t i = 0; i < n;) {
    if (text[i] != '<') {
      line += text[i] == '\n';
      ++i;
      continue;
    }
    if (text.compare(i, 4, "<!--") == 0) {
      skip_to(i, "-->");
    } else if (text.compare(i, 9, "<![CDATA[") == 0) {
      skip_to(i, "]]>");
    } else if (text.compare(i, 2, "<!") == 0) {
      skip_to(i, ">");
    } else if (text.compare(i, 2, "<?") == 0 || text.compare(i, 2, "</") == 0) {
      const bool close = text[i + 1] == '/';
      skip_tag(i);
      if (close && depth > 0) --depth;
    } else {
      const int at = line;
      if (!skip_tag(i) && ++depth > max_depth)
        throw std::runtime_error("line " + std::to_string(at) + ": elements nested deeper than " +
                                 std::to_string(max_depth) + " (the bound)");
    }
  }
}

}  // namespace featherdrive::xml_text
