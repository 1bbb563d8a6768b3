// The checks an MJCF document gets before MuJoCo's compiler reads it: MuJoCo 2.2.2 recurses per
// nesting level (includes followed), opens a FIFO named by an <include> or an asset and waits,
// takes time quadratic in keyframes, allocates what <size> asks and reads "nan" as its default.
#pragma once

#include <mujoco/mujoco.h>

#include <filesystem>
#include <string>
#include <vector>

namespace featherdrive::mjcf_document {

/// Reads the document `filename` as mj_loadXML would (from `vfs` when it holds the name, else
/// from disk), follows its includes and resolves its mesh, skin, hfield and texture files as
/// MuJoCo does (<compiler meshdir texturedir strippath>, relative to the model file's folder).
/// Throws InputError, one line starting with `shown`, for: a file that read_input_file refuses
/// (a FIFO, a folder, a device, over 64 MiB, missing), a referenced file that is not a regular
/// file, elements nested deeper than kMaxMjcfDepth with includes followed, more than
/// kMaxMjcfIncludes includes or a document over 64 MiB in all, a root element other than
/// <mujoco>, a numeric attribute that reads as NaN or infinity, and the <size> counts and
/// keyframes above their bounds (mjcf.hpp). Returns the files it read or checked on disk.
std::vector<std::filesystem::path> check(const std::string& filename, const mjVFS* vfs,
                                         const std::string& shown);

}  // namespace featherdrive::mjcf_document
