// The node's private parameters -> the scene YAML tree. The node and cloth_bench then share one
// reader (sceneFromYaml): the same defaults, the same validation, the same error messages.
#pragma once

#include <string>
#include <vector>

#include <ros/node_handle.h>
#include <xmlrpcpp/XmlRpcValue.h>
#include <yaml-cpp/yaml.h>

#include "pbd_cloth/config/scene_config.h"
#include "pbd_cloth/ros/cloth_ros.h"

namespace pbd_cloth {

// Top-level scene keys the node owns. Other parameters in the private namespace (e.g. written by
// dynamic_reconfigure or by a user's launch file) are left alone.
const std::vector<std::string>& sceneParameterKeys();

// Converts one parameter tree. `key` is its dotted name, used in the ConfigError thrown for types
// YAML has no equivalent for (date/time, binary).
YAML::Node yamlFromXmlRpc(XmlRpc::XmlRpcValue& value, const std::string& key);

// The scene keys present under `nh_private` as one YAML map (empty when none is set).
YAML::Node sceneYamlFromParameters(const ros::NodeHandle& nh_private);

// Reads and validates the scene; throws ConfigError naming the bad key and its allowed range.
SceneConfig readSceneParameters(const ros::NodeHandle& nh_private);

// The node's own settings beside the scene (~tf_timeout, ~pose_period, ~max_pose_period,
// ~min_real_time_factor, ~max_catch_up_steps, ~publish_clock, ~max_real_time_factor,
// ~robot_tf_timeout); a missing
// key keeps its default, a bad value or type throws ConfigError naming the key and its range.
ClothRos::Config readNodeParameters(const ros::NodeHandle& nh_private);

}  // namespace pbd_cloth
