#include "pbd_cloth/ros/ros_params.h"

#include <cmath>
#include <sstream>

#include <ros/console.h>

#include "pbd_cloth/scene/scene_yaml.h"

namespace pbd_cloth {

const std::vector<std::string>& sceneParameterKeys() {
  static const std::vector<std::string> keys = {"frame_id",  "step_rate", "publish_rate", "solver",
                                                "cloth",     "granular",  "grippers",     "bounds",
                                                "obstacles", "robot",     "cameras"};
  return keys;
}

YAML::Node yamlFromXmlRpc(XmlRpc::XmlRpcValue& value, const std::string& key) {
  switch (value.getType()) {
    case XmlRpc::XmlRpcValue::TypeBoolean:
      return YAML::Node(static_cast<bool>(value));
    case XmlRpc::XmlRpcValue::TypeInt:
      return YAML::Node(static_cast<int>(value));
    case XmlRpc::XmlRpcValue::TypeDouble:
      // yaml-cpp writes doubles with max_digits10, so the value round-trips exactly.
      return YAML::Node(static_cast<double>(value));
    case XmlRpc::XmlRpcValue::TypeString:
      return YAML::Node(static_cast<std::string>(value));
    case XmlRpc::XmlRpcValue::TypeArray: {
      // Built as an explicit sequence so an empty list (point_masses: []) stays a list.
      YAML::Node node(YAML::NodeType::Sequence);
      for (int i = 0; i < value.size(); ++i) {
        node.push_back(yamlFromXmlRpc(value[i], key + "." + std::to_string(i)));
      }
      return node;
    }
    case XmlRpc::XmlRpcValue::TypeStruct: {
      YAML::Node node(YAML::NodeType::Map);
      for (auto& member : value) {
        node[member.first] = yamlFromXmlRpc(member.second, key + "." + member.first);
      }
      return node;
    }
    case XmlRpc::XmlRpcValue::TypeInvalid:
      return YAML::Node(YAML::NodeType::Null);
    default:
      throw ConfigError(key, "unsupported parameter type (use numbers, strings, lists or maps)");
  }
}

YAML::Node sceneYamlFromParameters(const ros::NodeHandle& nh_private) {
  YAML::Node root(YAML::NodeType::Map);
  for (const std::string& key : sceneParameterKeys()) {
    XmlRpc::XmlRpcValue value;
    if (nh_private.getParam(key, value)) {
      root[key] = yamlFromXmlRpc(value, key);
    }
  }
  return root;
}

SceneConfig readSceneParameters(const ros::NodeHandle& nh_private) {
  const YAML::Node root = sceneYamlFromParameters(nh_private);
  if (root.size() == 0) {
    ROS_WARN(
        "No scene parameters under %s (load a scene YAML with <rosparam>); using the defaults.",
        nh_private.getNamespace().c_str());
  }
  return sceneFromYaml(root);
}

ClothRos::Config readNodeParameters(const ros::NodeHandle& nh_private) {
  ClothRos::Config config;
  // A parameter of the wrong type (a string where a number belongs) is an error too, not a
  // silent default: the user meant to set something.
  const auto present = [&nh_private](const std::string& key, XmlRpc::XmlRpcValue& value) {
    return nh_private.getParam(key, value);
  };
  // `low` is allowed when `low_allowed`; every value must be finite.
  const auto read = [&](const std::string& key, double& value, double low, bool low_allowed) {
    XmlRpc::XmlRpcValue raw;
    if (!present(key, raw)) {
      return;
    }
    std::ostringstream message;
    message << "must be a finite number " << (low_allowed ? ">= " : "> ") << low << ", got ";
    if (raw.getType() == XmlRpc::XmlRpcValue::TypeInt) {
      value = static_cast<int>(raw);
    } else if (raw.getType() == XmlRpc::XmlRpcValue::TypeDouble) {
      value = static_cast<double>(raw);
    } else {
      message << "a value that is not a number";
      throw ConfigError(key, message.str());
    }
    if (!std::isfinite(value) || value < low || (!low_allowed && value == low)) {
      message << value;
      throw ConfigError(key, message.str());
    }
  };
  const auto readInt = [&](const std::string& key, int& value, int low, int high) {
    XmlRpc::XmlRpcValue raw;
    if (!present(key, raw)) {
      return;
    }
    std::ostringstream message;
    message << "must be an integer in [" << low << ", " << high << "], got ";
    if (raw.getType() != XmlRpc::XmlRpcValue::TypeInt) {
      message << "a value that is not an integer";
      throw ConfigError(key, message.str());
    }
    value = static_cast<int>(raw);
    if (value < low || value > high) {
      message << value;
      throw ConfigError(key, message.str());
    }
  };
  const auto readBool = [&](const std::string& key, bool& value) {
    XmlRpc::XmlRpcValue raw;
    if (!present(key, raw)) {
      return;
    }
    if (raw.getType() != XmlRpc::XmlRpcValue::TypeBoolean) {
      throw ConfigError(key, "must be true or false");
    }
    value = static_cast<bool>(raw);
  };
  read("tf_timeout", config.tf_timeout, 0.0, true);
  read("pose_period", config.follower.default_period, 0.0, false);
  read("max_pose_period", config.follower.max_period, 0.0, false);
  read("min_real_time_factor", config.diagnostics.min_real_time_factor, 0.0, true);
  // An upper bound keeps a typo (10000) from stalling the callback queue for seconds of catch-up.
  readInt("max_catch_up_steps", config.max_catch_up_steps, 1, 1000);
  readBool("publish_clock", config.publish_clock);
  read("max_real_time_factor", config.max_real_time_factor, 0.0, true);
  read("robot_tf_timeout", config.robot_tf_timeout, 0.0, false);
  read("body_tf_timeout", config.body_tf_timeout, 0.0, false);
  readBool("fault_injection", config.fault_injection);
  if (config.max_real_time_factor > 0.0 && !config.publish_clock) {
    ROS_WARN(
        "%s is %g but %s is false: the limit applies only when the node is the clock; ignored.",
        nh_private.resolveName("max_real_time_factor").c_str(), config.max_real_time_factor,
        nh_private.resolveName("publish_clock").c_str());
  }
  return config;
}

}  // namespace pbd_cloth
