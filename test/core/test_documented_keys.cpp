// config/hanging.yaml says it lists every key the scene reader accepts. This test holds it to that:
// the keys it lists (live, or commented out as `# key: value`) are compared, map by map, with the
// keys the reader itself names when it refuses an unknown one ("known here: ..."), so neither list
// can grow without the other.
#include <gtest/gtest.h>

#include <fstream>
#include <map>
#include <regex>
#include <set>
#include <sstream>
#include <string>

#include "pbd_cloth/scene/scene_yaml.h"

namespace pbd_cloth {
namespace {

using KeySet = std::set<std::string>;

std::string readText(const std::string& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

// hanging.yaml with its commented-out keys made live: a comment line whose text is a key
// (`# name: ...`, `#   radius: ...`) or a list item (`#   - {t: ...}`) loses its `# `. Prose
// comments start with a capital, a word followed by a space, or a parenthesis, and stay comments.
std::string uncommentKeys(const std::string& text) {
  static const std::regex kCommentedKey(R"(^(\s*)# (\s*(- |[a-z_]+:( |$)).*)$)");
  std::istringstream lines(text);
  std::string line, out;
  while (std::getline(lines, line)) {
    std::smatch match;
    if (std::regex_match(line, match, kCommentedKey)) line = match[1].str() + match[2].str();
    out += line + "\n";
  }
  return out;
}

// Every map's keys, by path: "solver", "grippers[]", "grippers[].trajectory[]", ... ("" is the
// top level). Obstacles are gathered under "obstacles[]" whatever their shape. Joint names under
// robot.joint_trajectory[].positions are the URDF's, not the reader's, and are left out.
void collectKeys(const YAML::Node& node, const std::string& path,
                 std::map<std::string, KeySet>& keys) {
  if (node.IsMap()) {
    KeySet& here = keys[path];
    for (const auto& entry : node) {
      const std::string name = entry.first.Scalar();
      here.insert(name);
      const std::string child = path.empty() ? name : path + "." + name;
      if (child == "robot.joint_trajectory[].positions") continue;
      collectKeys(entry.second, child, keys);
    }
  } else if (node.IsSequence()) {
    for (const auto& item : node) collectKeys(item, path + "[]", keys);
  }
}

// The keys the reader names when it refuses `zz_unknown` in the map that `scene` puts it in
// ("unknown key (known here: a, b)" or, for an obstacle, "not used by a sphere (it takes a, b)").
KeySet readerKeys(const std::string& scene) {
  try {
    sceneFromYaml(YAML::Load(scene));
  } catch (const ConfigError& error) {
    const std::string message = error.what();
    static const std::regex kList(R"(\((?:known here|it takes): ([a-z0-9_, ]+)\))");
    std::smatch match;
    if (!std::regex_search(message, match, kList)) {
      ADD_FAILURE() << "no key list in the reader's refusal of " << scene << ": " << message;
      return {};
    }
    KeySet keys;
    std::istringstream names(match[1].str());
    std::string name;
    while (std::getline(names, name, ',')) keys.insert(name.substr(name.find_first_not_of(' ')));
    EXPECT_TRUE(error.key().find("zz_unknown") != std::string::npos) << message;
    return keys;
  }
  ADD_FAILURE() << "the reader accepted the unknown key in " << scene;
  return {};
}

TEST(SceneYaml, HangingYamlListsEveryKeyTheReaderAccepts) {
  const std::string path = std::string(PBD_CLOTH_SOURCE_DIR) + "/config/hanging.yaml";
  const std::string text = readText(path);
  ASSERT_FALSE(text.empty()) << path;
  std::map<std::string, KeySet> documented;
  collectKeys(YAML::Load(uncommentKeys(text)), "", documented);

  // Where the reader's maps are, and a scene that puts an unknown key in each.
  const std::map<std::string, std::string> probes = {
      {"", "{zz_unknown: 1}"},
      {"solver", "{solver: {zz_unknown: 1}}"},
      {"cloth", "{cloth: {zz_unknown: 1}}"},
      {"cloth.friction", "{cloth: {friction: {zz_unknown: 1}}}"},
      {"granular", "{granular: {zz_unknown: 1}}"},
      {"granular.region", "{granular: {region: {zz_unknown: 1}}}"},
      {"ropes[]", "{ropes: [{zz_unknown: 1}]}"},
      {"grippers[]", "{grippers: [{zz_unknown: 1}]}"},
      {"grippers[].trajectory[]", "{grippers: [{name: g, trajectory: [{zz_unknown: 1}]}]}"},
      {"bounds", "{bounds: {zz_unknown: 1}}"},
      {"robot", "{robot: {zz_unknown: 1}}"},
      {"robot.friction", "{robot: {friction: {zz_unknown: 1}}}"},
      {"robot.joint_trajectory[]", "{robot: {joint_trajectory: [{zz_unknown: 1}]}}"},
      {"cameras[]", "{cameras: [{zz_unknown: 1}]}"},
      {"cameras[].range", "{cameras: [{range: {zz_unknown: 1}}]}"},
  };
  std::map<std::string, KeySet> accepted;
  for (const auto& probe : probes) accepted[probe.first] = readerKeys(probe.second);
  // Obstacles: each shape's keys; the documented entries together must cover all of them.
  for (const char* shape : {"sphere", "box", "capsule", "cylinder", "plane", "mesh"}) {
    for (const std::string& key :
         readerKeys(std::string("{obstacles: [{shape: ") + shape + ", zz_unknown: 1}]}")) {
      accepted["obstacles[]"].insert(key);
    }
  }
  // The one top-level key read and ignored (scene_yaml.h); the reader's list does not name it.
  accepted[""].insert("description");

  for (const auto& map : accepted) {
    EXPECT_GE(map.second.size(), 2u) << "the reader named too few keys for '" << map.first << "'";
    EXPECT_EQ(documented[map.first], map.second)
        << "config/hanging.yaml's keys of '" << map.first << "' are not the reader's";
  }
  for (const auto& map : documented) {
    EXPECT_TRUE(accepted.count(map.first))
        << "config/hanging.yaml documents a map '" << map.first << "' this test does not check";
  }
  // The shipped file, as it is (optional parts commented out), loads.
  EXPECT_NO_THROW(loadScene(path));
}

}  // namespace
}  // namespace pbd_cloth
