// Checks on XML text before TinyXML 2.6 (urdfdom's XML reader, also the COLLADA reader's) reads
// it: TinyXML reads past the buffer on a cut-short UTF-8 sequence and recurses once per level.
#pragma once

#include <string>

namespace featherdrive::xml_text {

/// Throws std::runtime_error "line L, column C (byte B): not valid UTF-8 (byte 0xNN)" (or "a NUL
/// character") at the first byte that is not valid UTF-8.
void check_utf8(const std::string& text);

/// Throws std::runtime_error "line L: elements nested deeper than N (the bound)" where elements
/// nest deeper than `max_depth`.
void check_nesting(const std::string& text, int max_depth);

}  // namespace featherdrive::xml_text
