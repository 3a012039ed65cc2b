// The YAML reader beside the core: turns a scene YAML (the file cloth_bench and the tests load, or
// the node's private parameter tree converted to YAML) into a validated SceneConfig.
#pragma once

#include <string>

#include <yaml-cpp/yaml.h>

#include "pbd_cloth/config/scene_config.h"

namespace pbd_cloth {

// Parses and validates. Missing keys keep their defaults; an unknown key, a repeated key, a wrong
// type or a value out of range throws ConfigError naming the key (e.g. "solver.substeps", list
// entries as "grippers[0].radius") and the allowed range.
// - Unknown keys are refused at every level, the top level included. The only top-level keys that
//   are accepted and ignored (the allow-list) are: `description` (free text about the scene). The
//   ROS node passes only the scene keys of its private namespace (sceneParameterKeys()).
// - A key given as null (`solver:` with nothing under it) reads as absent: sections keep their
//   defaults, lists are empty, strings are "", and `bounds:` stays disabled. `bounds: {}` enables
//   the default box.
// - Integers may be written as 10.0. Poses are [x, y, z, qx, qy, qz, qw]; the quaternion is
//   normalized, a zero one is refused. Waypoint `grasp` absent reads as -1 (no change).
// - Obstacle keys of another shape (a radius on a box) are refused; `shape` is required. A mesh
//   obstacle requires `mesh`; its `scale` is [sx, sy, sz] or one number for all axes.
// - Files: after parsing, every mesh obstacle's file and, when robot.urdf_file is set, the URDF
//   (with its link meshes) are loaded (scene_assets.h), then the whole scene is validated. A
//   relative path (obstacles[i].mesh, robot.urdf_file) is relative to `base_directory` ("" = the
//   current directory; loadScene passes the YAML file's directory) and is stored resolved. file://
//   and package:// URIs go through resource_retriever (package:// needs the package on
//   ROS_PACKAGE_PATH, as a sourced workspace has it). Relative mesh paths inside a URDF file are
//   relative to that file. What loads but deserves a warning (an open mesh, a selected link
//   without collision elements) is listed in SceneConfig::load_warnings.
SceneConfig sceneFromYaml(const YAML::Node& root, const std::string& base_directory = "");

// Loads a file and parses it as above, relative paths relative to the file's directory. Throws
// ConfigError (key "file") when it cannot be read.
SceneConfig loadScene(const std::string& path);
YAML::Node loadSceneYaml(const std::string& path);
// The base directory of the scene file `path` for sceneFromYaml ("" for a bare file name).
std::string sceneFileDirectory(const std::string& path);

// Applies one "dotted.key=value" override (cloth_bench --set), e.g. "solver.substeps=20",
// "cloth.pinned=[0, 49]", "grippers.0.radius=0.03". The value is parsed as YAML. Missing map keys
// are created; a list index equal to the list's size appends ("grippers.1.name=right"). Throws
// ConfigError for a malformed assignment; the keys themselves are checked by sceneFromYaml.
void applyOverride(YAML::Node& root, const std::string& assignment);

}  // namespace pbd_cloth
