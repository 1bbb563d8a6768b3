// Reads a scene's fit: section (fit_spec.cpp) for parse_scene, once the rest of the scene is read.
#pragma once

#include "featherdrive/io/fit_spec.hpp"
#include "featherdrive/io/scene.hpp"
#include "yaml_reader.hpp"

namespace featherdrive {

/// Throws InputError naming the file, fit's key path and the value.
FitSpec read_fit_spec(const scene_yaml::Reader& r, const YAML::Node& node, const Scene& scene);

}  // namespace featherdrive
