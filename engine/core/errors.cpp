/// @file errors.cpp
/// @brief Message formatting of the typed input errors.
#include "engine/core/errors.hpp"

#include <utility>

namespace sph {

// One line, always in this order, so that users (and tests) can rely on the shape:
//   <file>: <json-path>: found <value>, expected <what>
SceneError::SceneError(std::string file, std::string json_path, std::string found,
                       std::string expected)
    : InputError(file + ": " + json_path + ": found " + found + ", expected " + expected),
      m_file(std::move(file)),
      m_path(std::move(json_path)) {}

}  // namespace sph
