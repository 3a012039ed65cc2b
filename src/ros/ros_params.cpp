#include "pbd_cloth/ros/ros_params.h"

#include <ros/console.h>

#include "pbd_cloth/scene_yaml.h"

namespace pbd_cloth {

const std::vector<std::string>& sceneParameterKeys() {
  static const std::vector<std::string> keys = {"frame_id", "step_rate", "publish_rate",
                                                "solver",   "cloth",     "granular",
                                                "grippers", "bounds",    "obstacles"};
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

}  // namespace pbd_cloth
