// The files a scene refers to: mesh files (assimp) and the robot's URDF (ROS's urdf package, which
// parses with urdfdom). Plain paths are read with the standard library; file:// and package:// URIs
// go through resource_retriever, as rviz and robot_state_publisher resolve them, so a URDF that
// displays in rviz loads here too. No ROS master is involved.
#include "pbd_cloth/scene/scene_assets.h"

#include "pbd_cloth/sim/mesh_cloth.h"

#include <assimp/config.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <console_bridge/console.h>
#include <resource_retriever/retriever.h>
#include <tiny_obj_loader.h>
#include <tinyxml2.h>
#include <urdf/model.h>
#include <assimp/Importer.hpp>

#include <poll.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <chrono>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <stdexcept>

namespace pbd_cloth {
namespace {

bool startsWith(const std::string& text, const std::string& prefix) {
  return text.compare(0, prefix.size(), prefix) == 0;
}

bool isUri(const std::string& location) {
  return startsWith(location, "package://") || startsWith(location, "file://");
}

std::string joinNames(const std::vector<std::string>& names) {
  std::string out;
  for (const std::string& name : names) out += (out.empty() ? "" : ", ") + name;
  return out.empty() ? "none" : out;
}

// The bytes of a file. `what` says what the file is for ("mesh file", "URDF file") in messages.
std::string readLocation(const std::string& location, const std::string& key,
                         const std::string& what) {
  const std::string named = what + " '" + location + "'";
  if (isUri(location)) {
    try {
      resource_retriever::Retriever retriever;
      const resource_retriever::MemoryResource resource = retriever.get(location);
      return std::string(reinterpret_cast<const char*>(resource.data.get()), resource.size);
    } catch (const std::exception& e) {
      // package:// needs the package on ROS_PACKAGE_PATH (a sourced workspace has it).
      throw ConfigError(key, named + " cannot be read: " + e.what());
    }
  }
  std::error_code error;
  const std::filesystem::file_status status = std::filesystem::status(location, error);
  if (!std::filesystem::exists(status)) {
    throw ConfigError(key, named + " not found");
  }
  if (std::filesystem::is_directory(status)) {
    throw ConfigError(key, named + " is a directory, not a file");
  }
  std::ifstream in(location, std::ios::binary);
  if (!in.is_open()) throw ConfigError(key, named + " cannot be opened (permissions?)");
  std::ostringstream bytes;
  bytes << in.rdbuf();
  if (in.bad()) throw ConfigError(key, named + " cannot be read");
  return bytes.str();
}

// The file extension, lowercase, without the dot: assimp's format hint for a memory buffer.
std::string extensionOf(const std::string& location) {
  const std::size_t slash = location.find_last_of('/');
  const std::size_t dot = location.find_last_of('.');
  if (dot == std::string::npos || (slash != std::string::npos && dot < slash)) return "";
  std::string extension = location.substr(dot + 1);
  std::transform(extension.begin(), extension.end(), extension.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return extension;
}

// Every triangle of every mesh below `node`, in the file's frame (node transforms applied).
void collectTriangles(const aiScene& scene, const aiNode& node, const aiMatrix4x4& parent,
                      std::vector<TriangleMesh::Vec3>& vertices,
                      std::vector<TriangleMesh::Triangle>& triangles) {
  const aiMatrix4x4 transform = parent * node.mTransformation;
  // A mirroring transform turns the winding, and with it the outward normals, inside out.
  const bool mirrored = transform.Determinant() < 0.0f;
  for (unsigned m = 0; m < node.mNumMeshes; ++m) {
    const aiMesh& mesh = *scene.mMeshes[node.mMeshes[m]];
    const int base = static_cast<int>(vertices.size());
    for (unsigned v = 0; v < mesh.mNumVertices; ++v) {
      const aiVector3D p = transform * mesh.mVertices[v];
      vertices.emplace_back(p.x, p.y, p.z);
    }
    for (unsigned f = 0; f < mesh.mNumFaces; ++f) {
      const aiFace& face = mesh.mFaces[f];
      if (face.mNumIndices != 3) continue;  // points and lines: no surface
      const int a = base + static_cast<int>(face.mIndices[0]);
      const int b = base + static_cast<int>(face.mIndices[1]);
      const int c = base + static_cast<int>(face.mIndices[2]);
      triangles.push_back(mirrored ? TriangleMesh::Triangle{a, c, b}
                                   : TriangleMesh::Triangle{a, b, c});
    }
  }
  for (unsigned k = 0; k < node.mNumChildren; ++k) {
    collectTriangles(scene, *node.mChildren[k], transform, vertices, triangles);
  }
}

// urdfdom says why a URDF does not parse only through console_bridge's log; this handler keeps the
// error lines for the ConfigError and passes everything else on to the handler it replaces.
class ConsoleErrorCapture : public console_bridge::OutputHandler {
 public:
  ConsoleErrorCapture() : previous_(console_bridge::getOutputHandler()) {
    console_bridge::useOutputHandler(this);
  }
  ~ConsoleErrorCapture() override { console_bridge::restorePreviousOutputHandler(); }
  ConsoleErrorCapture(const ConsoleErrorCapture&) = delete;
  ConsoleErrorCapture& operator=(const ConsoleErrorCapture&) = delete;

  void log(const std::string& text, console_bridge::LogLevel level, const char* filename,
           int line) override {
    if (level >= console_bridge::CONSOLE_BRIDGE_LOG_ERROR) {
      errors_ += (errors_.empty() ? "" : "; ") + text;
    } else if (previous_ != nullptr) {
      previous_->log(text, level, filename, line);
    }
  }
  const std::string& errors() const { return errors_; }

 private:
  console_bridge::OutputHandler* previous_;
  std::string errors_;
};

Pose toPose(const urdf::Pose& pose) {
  Pose out;
  out.position = Eigen::Vector3d(pose.position.x, pose.position.y, pose.position.z);
  out.orientation =
      Eigen::Quaterniond(pose.rotation.w, pose.rotation.x, pose.rotation.y, pose.rotation.z);
  if (out.orientation.norm() > 0.0) out.orientation.normalize();
  return out;
}

Eigen::Vector3d toVector(const urdf::Vector3& v) { return Eigen::Vector3d(v.x, v.y, v.z); }

JointType toJointType(int type, const std::string& joint, const std::string& source) {
  switch (type) {
    case urdf::Joint::REVOLUTE:
      return JointType::kRevolute;
    case urdf::Joint::CONTINUOUS:
      return JointType::kContinuous;
    case urdf::Joint::PRISMATIC:
      return JointType::kPrismatic;
    case urdf::Joint::FLOATING:
      return JointType::kFloating;
    case urdf::Joint::PLANAR:
      return JointType::kPlanar;
    case urdf::Joint::FIXED:
      return JointType::kFixed;
    default:
      throw ConfigError(source, "joint '" + joint + "' has an unknown type");
  }
}

// The geometry element names of each link's <collision> elements, in file order, read from the
// XML itself: urdfdom drops a collision element whose geometry it does not know (a <capsule>),
// logging an error but still returning the model, which would leave that part of the link
// silently without collision.
std::map<std::string, std::vector<std::string>> collisionGeometryNames(const std::string& xml) {
  std::map<std::string, std::vector<std::string>> names;
  tinyxml2::XMLDocument document;
  if (document.Parse(xml.c_str(), xml.size()) != tinyxml2::XML_SUCCESS) return names;
  const tinyxml2::XMLElement* robot = document.FirstChildElement("robot");
  if (robot == nullptr) return names;
  for (const tinyxml2::XMLElement* link = robot->FirstChildElement("link"); link != nullptr;
       link = link->NextSiblingElement("link")) {
    const char* name = link->Attribute("name");
    if (name == nullptr) continue;
    std::vector<std::string>& geometries = names[name];
    for (const tinyxml2::XMLElement* collision = link->FirstChildElement("collision");
         collision != nullptr; collision = collision->NextSiblingElement("collision")) {
      const tinyxml2::XMLElement* geometry = collision->FirstChildElement("geometry");
      const tinyxml2::XMLElement* shape =
          geometry != nullptr ? geometry->FirstChildElement() : nullptr;
      geometries.push_back(shape != nullptr ? shape->Name() : "");
    }
  }
  return names;
}

// Refuses a selected link whose <collision> elements urdfdom did not all keep.
void checkCollisionsKept(const urdf::Link& link, const std::vector<std::string>& geometries,
                         const std::string& parse_errors) {
  static const std::vector<std::string> kSupported = {"box", "sphere", "cylinder", "mesh"};
  for (std::size_t c = 0; c < geometries.size(); ++c) {
    if (std::find(kSupported.begin(), kSupported.end(), geometries[c]) == kSupported.end()) {
      throw ConfigError(
          "robot link '" + link.name + "' collision " + std::to_string(c),
          "unsupported geometry '" + geometries[c] + "' (supported: box, sphere, cylinder, mesh)");
    }
  }
  if (geometries.size() != link.collision_array.size()) {
    throw ConfigError("robot link '" + link.name + "'",
                      std::to_string(geometries.size()) + " collision elements in the URDF, " +
                          std::to_string(link.collision_array.size()) +
                          " parsed (urdfdom: " + parse_errors + ")");
  }
}

// Meshes loaded by one loadRobot call, so links sharing a file share its distance structure.
using MeshCache =
    std::map<std::pair<std::string, std::vector<double>>, std::shared_ptr<const TriangleMesh>>;

// One <collision> element as a shape in the link frame.
ObstacleConfig collisionShape(const urdf::Collision& collision, const std::string& link,
                              std::size_t index, const RobotConfig& robot,
                              const std::string& base_directory, MeshCache& meshes,
                              std::vector<std::string>& warnings) {
  const std::string key = "robot link '" + link + "' collision " + std::to_string(index);
  ObstacleConfig o;
  o.name = link + "/" + std::to_string(index);
  o.pose = toPose(collision.origin);
  o.padding = robot.padding;
  o.has_friction = true;
  o.friction = robot.friction;
  const urdf::Geometry* geometry = collision.geometry.get();
  if (geometry == nullptr) throw ConfigError(key, "has no geometry");
  switch (geometry->type) {
    case urdf::Geometry::SPHERE:
      o.shape = ShapeType::kSphere;
      o.radius = static_cast<const urdf::Sphere*>(geometry)->radius;
      return o;
    case urdf::Geometry::BOX:
      o.shape = ShapeType::kBox;
      o.size = toVector(static_cast<const urdf::Box*>(geometry)->dim);
      return o;
    case urdf::Geometry::CYLINDER: {
      const auto* cylinder = static_cast<const urdf::Cylinder*>(geometry);
      o.shape = ShapeType::kCylinder;
      o.radius = cylinder->radius;
      o.length = cylinder->length;
      return o;
    }
    case urdf::Geometry::MESH: {
      const auto* mesh = static_cast<const urdf::Mesh*>(geometry);
      o.shape = ShapeType::kMesh;
      o.mesh = resolveScenePath(mesh->filename, base_directory);
      o.scale = toVector(mesh->scale);
      std::shared_ptr<const TriangleMesh>& cached =
          meshes[{o.mesh, {o.scale.x(), o.scale.y(), o.scale.z()}}];
      if (!cached) cached = loadMesh(o.mesh, o.scale, key + " mesh", warnings);
      o.mesh_data = cached;
      return o;
    }
    default:
      throw ConfigError(key, "unsupported geometry (type " + std::to_string(geometry->type) +
                                 "; supported: box, sphere, cylinder, mesh)");
  }
}

void loadRobotFrom(SceneConfig& scene, const std::string& urdf_xml, const std::string& source,
                   const std::string& base_directory) {
  urdf::Model urdf;
  bool parsed = false;
  std::string reason;
  {
    ConsoleErrorCapture capture;
    try {
      parsed = urdf.initString(urdf_xml);
    } catch (const std::exception& e) {
      reason = e.what();
    }
    if (!capture.errors().empty()) reason += (reason.empty() ? "" : "; ") + capture.errors();
  }
  if (!parsed || !urdf.getRoot()) {
    throw ConfigError(source, "does not parse as URDF" + (reason.empty() ? "" : ": " + reason));
  }
  const std::map<std::string, std::vector<std::string>> geometries =
      collisionGeometryNames(urdf_xml);

  RobotConfig& robot = scene.robot;
  RobotModel model;
  model.name = urdf.getName();

  // Links in tree order from the root (a parent before its children), so a reader of the model
  // meets the tree top-down.
  std::vector<urdf::LinkConstSharedPtr> order{urdf.getRoot()};
  for (std::size_t k = 0; k < order.size(); ++k) {
    for (const urdf::LinkSharedPtr& child : order[k]->child_links) order.push_back(child);
  }
  std::map<std::string, int> link_index;
  for (const urdf::LinkConstSharedPtr& link : order) {
    link_index[link->name] = static_cast<int>(model.links.size());
    RobotLink out;
    out.name = link->name;
    model.links.push_back(out);
  }
  model.root_link = 0;

  // The selection: every link with collision elements, or robot.links.
  std::vector<std::string> with_collisions;
  for (const urdf::LinkConstSharedPtr& link : order) {
    if (!link->collision_array.empty()) with_collisions.push_back(link->name);
  }
  std::vector<bool> selected(order.size(), robot.links.empty());
  for (std::size_t k = 0; k < robot.links.size(); ++k) {
    const std::string key = "robot.links[" + std::to_string(k) + "]";
    const auto found = link_index.find(robot.links[k]);
    if (found == link_index.end()) {
      throw ConfigError(key, "no link '" + robot.links[k] +
                                 "' in the URDF (links with collision elements: " +
                                 joinNames(with_collisions) + ")");
    }
    selected[found->second] = true;
    if (order[found->second]->collision_array.empty()) {
      scene.load_warnings.push_back(key + ": link '" + robot.links[k] +
                                    "' has no collision element: it cannot touch the cloth");
    }
  }

  MeshCache meshes;
  for (std::size_t k = 0; k < order.size(); ++k) {
    if (!selected[k]) continue;
    const urdf::Link& link = *order[k];
    const auto in_file = geometries.find(link.name);
    checkCollisionsKept(
        link, in_file != geometries.end() ? in_file->second : std::vector<std::string>(), reason);
    // The whole array: link->collision is only its first element.
    for (std::size_t c = 0; c < link.collision_array.size(); ++c) {
      if (!link.collision_array[c]) continue;
      model.links[k].collisions.push_back(collisionShape(*link.collision_array[c], link.name, c,
                                                         robot, base_directory, meshes,
                                                         scene.load_warnings));
    }
  }

  // Joints in the order of their child links, so the tree is walked top-down in index order.
  for (std::size_t k = 1; k < order.size(); ++k) {
    const urdf::JointConstSharedPtr& joint = order[k]->parent_joint;
    if (!joint) continue;
    RobotJoint out;
    out.name = joint->name;
    out.type = toJointType(joint->type, joint->name, source);
    out.parent_link = link_index.at(joint->parent_link_name);
    out.child_link = static_cast<int>(k);
    out.origin = toPose(joint->parent_to_joint_origin_transform);
    out.axis = toVector(joint->axis);
    const bool moves = out.type == JointType::kRevolute || out.type == JointType::kContinuous ||
                       out.type == JointType::kPrismatic;
    if (moves) {
      if (!(out.axis.norm() > 0.0) || !out.axis.allFinite()) {
        throw ConfigError(source, "joint '" + joint->name + "' has a zero or non-finite axis");
      }
      out.axis.normalize();
    }
    if (joint->limits) {
      out.lower = joint->limits->lower;
      out.upper = joint->limits->upper;
    }
    model.links[k].parent_joint = static_cast<int>(model.joints.size());
    model.joints.push_back(out);
  }
  for (std::size_t k = 1; k < order.size(); ++k) {
    const urdf::JointConstSharedPtr& joint = order[k]->parent_joint;
    if (!joint || !joint->mimic) continue;
    RobotJoint& out = model.joints[model.links[k].parent_joint];
    out.mimic_joint = model.jointIndex(joint->mimic->joint_name);
    if (out.mimic_joint < 0) {
      throw ConfigError(source, "joint '" + joint->name + "' mimics '" + joint->mimic->joint_name +
                                    "', which is not in the URDF");
    }
    out.mimic_multiplier = joint->mimic->multiplier;
    out.mimic_offset = joint->mimic->offset;
  }
  // Mimic joints that follow each other round in a circle (a joint mimicking itself included) have
  // no position: refused here, by name, instead of reaching the forward kinematics (found by
  // test/fuzz/fuzz_urdf).
  for (std::size_t start = 0; start < model.joints.size(); ++start) {
    std::string chain = model.joints[start].name;
    int j = model.joints[start].mimic_joint;
    for (std::size_t hops = 0; j >= 0; ++hops) {
      chain += " -> " + model.joints[j].name;
      // Back at the start, or (a chain that runs into a cycle elsewhere) longer than any path.
      if (static_cast<std::size_t>(j) == start || hops >= model.joints.size()) {
        throw ConfigError(source, "mimic joints form a cycle: " + chain);
      }
      j = model.joints[j].mimic_joint;
    }
  }
  // What urdfdom logged as errors while still returning a model (an element it dropped, such as
  // a visual with an unknown geometry) is passed on.
  if (!reason.empty()) scene.load_warnings.push_back(source + ": urdfdom: " + reason);
  robot.model = std::move(model);
}

// --- assimp in a child process -------------------------------------------------------------------
// assimp 5.2 (Debian) aborts, or never returns, on some malformed files
// (test/fuzz/fuzz_mesh_obstacle found a PLY header without end, and a PLY that fails an assertion
// in its post-processing). A mesh file is user input, and the node must not die or hang on one, so
// assimp reads it in a forked child that sends the triangles back through a pipe; a child that
// crashes, or takes longer than kImportTimeout, becomes a ConfigError naming the file. fork()
// copies the process lazily (the file's bytes are already in memory), and glibc keeps malloc usable
// in the child of a threaded process.
constexpr std::chrono::seconds kImportTimeout{20};

void writeAll(int fd, const std::string& data) {
  std::size_t done = 0;
  while (done < data.size()) {
    const ssize_t n = ::write(fd, data.data() + done, data.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return;
    done += static_cast<std::size_t>(n);
  }
}

template <typename T>
void appendRaw(std::string& out, const T* data, std::size_t count) {
  out.append(reinterpret_cast<const char*>(data), count * sizeof(T));
}

// In the child: the file read by assimp as 'M' + counts + raw arrays, or 'E' + assimp's reason.
std::string importInChild(const std::string& bytes, const std::string& hint) {
  Assimp::Importer importer;
  // ROS meshes (rviz, Gazebo) are in the link frame as written: a COLLADA file's up_axis does not
  // rotate them. Its <unit meter> scale is applied, as rviz does.
  importer.SetPropertyBool(AI_CONFIG_IMPORT_COLLADA_IGNORE_UP_DIRECTION, true);
  const aiScene* scene = importer.ReadFileFromMemory(
      bytes.data(), bytes.size(), aiProcess_Triangulate | aiProcess_JoinIdenticalVertices,
      hint.c_str());
  if (scene == nullptr || scene->mRootNode == nullptr) {
    return "E" + std::string(importer.GetErrorString());
  }
  std::vector<TriangleMesh::Vec3> vertices;
  std::vector<TriangleMesh::Triangle> triangles;
  collectTriangles(*scene, *scene->mRootNode, aiMatrix4x4(), vertices, triangles);
  std::string out = "M";
  const std::uint64_t counts[2] = {vertices.size(), triangles.size()};
  appendRaw(out, counts, 2);
  for (const TriangleMesh::Vec3& v : vertices) appendRaw(out, v.data(), 3);
  for (const TriangleMesh::Triangle& t : triangles) appendRaw(out, t.data(), 3);
  return out;
}

// Empty on success (vertices and triangles filled), else what went wrong, to follow the file name.
std::string importIsolated(const std::string& bytes, const std::string& hint,
                           std::vector<TriangleMesh::Vec3>& vertices,
                           std::vector<TriangleMesh::Triangle>& triangles) {
  int fds[2];
  if (::pipe(fds) != 0) return "could not be read: pipe() failed: " + std::string(strerror(errno));
  std::fflush(nullptr);  // nothing buffered is written twice by the child
  const pid_t child = ::fork();
  if (child < 0) {
    ::close(fds[0]);
    ::close(fds[1]);
    return "could not be read: fork() failed: " + std::string(strerror(errno));
  }
  if (child == 0) {
    ::close(fds[0]);
    std::string out;
    try {
      out = importInChild(bytes, hint);
    } catch (const std::exception& e) {
      out = "E" + std::string(e.what());
    } catch (...) {
      out = "Eassimp threw an unknown exception";
    }
    writeAll(fds[1], out);
    ::close(fds[1]);
    ::_exit(0);  // no atexit handlers, no destructors of the parent's objects
  }
  ::close(fds[1]);
  std::string in;
  const auto deadline = std::chrono::steady_clock::now() + kImportTimeout;
  bool timed_out = false;
  char buffer[1 << 16];
  while (true) {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
        deadline - std::chrono::steady_clock::now());
    pollfd readable{fds[0], POLLIN, 0};
    const int ready = ::poll(&readable, 1, static_cast<int>(std::max<long long>(0, left.count())));
    if (ready < 0 && errno == EINTR) continue;
    if (ready == 0) {
      timed_out = true;
      break;
    }
    const ssize_t n = ::read(fds[0], buffer, sizeof(buffer));
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) break;
    in.append(buffer, static_cast<std::size_t>(n));
  }
  ::close(fds[0]);
  if (timed_out) ::kill(child, SIGKILL);
  int status = 0;
  while (::waitpid(child, &status, 0) < 0 && errno == EINTR) {
  }
  if (timed_out) {
    return "could not be read: assimp did not finish within " +
           std::to_string(kImportTimeout.count()) + " s (a malformed file)";
  }
  if (WIFSIGNALED(status)) {
    return "could not be read: assimp crashed on it (signal " + std::to_string(WTERMSIG(status)) +
           ", a malformed file)";
  }
  if (in.empty() || !(WIFEXITED(status) && WEXITSTATUS(status) == 0)) {
    return "could not be read: assimp failed on it (a malformed file)";
  }
  if (in[0] == 'E') {
    const std::string reason = in.substr(1);
    return "is not a mesh file assimp can read" + (reason.empty() ? "" : " (" + reason + ")");
  }
  std::uint64_t counts[2] = {0, 0};
  if (in[0] != 'M' || in.size() < 1 + sizeof(counts)) return "could not be read (assimp)";
  std::memcpy(counts, in.data() + 1, sizeof(counts));
  const std::size_t vertex_bytes = 3 * sizeof(double),
                    triangle_bytes = sizeof(TriangleMesh::Triangle);
  if (counts[0] > in.size() / vertex_bytes || counts[1] > in.size() / triangle_bytes ||
      in.size() != 1 + sizeof(counts) + counts[0] * vertex_bytes + counts[1] * triangle_bytes) {
    return "could not be read (assimp sent an incomplete mesh)";
  }
  vertices.resize(counts[0]);
  triangles.resize(counts[1]);
  const char* p = in.data() + 1 + sizeof(counts);
  for (TriangleMesh::Vec3& v : vertices) {
    std::memcpy(v.data(), p, vertex_bytes);
    p += vertex_bytes;
  }
  for (TriangleMesh::Triangle& t : triangles) {
    std::memcpy(t.data(), p, triangle_bytes);
    p += triangle_bytes;
  }
  return std::string();
}

}  // namespace

std::shared_ptr<const TriangleMesh> loadMesh(const std::string& uri, const Eigen::Vector3d& scale,
                                             const std::string& key,
                                             std::vector<std::string>& warnings) {
  if (uri.empty()) {
    throw ConfigError(key, "required: a mesh file path, file:// or package:// URI");
  }
  if (!scale.allFinite() || (scale.array() == 0.0).any()) {
    std::ostringstream text;
    text << "scale of mesh '" << uri << "' must be 3 finite non-zero numbers, got [" << scale.x()
         << ", " << scale.y() << ", " << scale.z() << "]";
    throw ConfigError(key, text.str());
  }
  const std::string named = "mesh file '" + uri + "'";
  const std::string bytes = readLocation(uri, key, "mesh file");
  if (bytes.empty()) throw ConfigError(key, named + " is empty");
  // assimp 5.2's PLY reader never returns on a header without its end (found by
  // test/fuzz/fuzz_mesh_obstacle); assimp recognises PLY by its first token, so check the same.
  if (bytes.compare(0, 3, "ply") == 0 && bytes.find("end_header") == std::string::npos) {
    throw ConfigError(key, named + " is a PLY file whose header has no end_header line");
  }

  std::vector<TriangleMesh::Vec3> vertices;
  std::vector<TriangleMesh::Triangle> triangles;
  const std::string failure = importIsolated(bytes, extensionOf(uri), vertices, triangles);
  if (!failure.empty()) throw ConfigError(key, named + " " + failure);
  if (triangles.empty()) throw ConfigError(key, named + " has no triangles");

  for (TriangleMesh::Vec3& v : vertices) v = v.cwiseProduct(scale);
  // An odd number of negative scale factors mirrors the mesh: keep the normals outward.
  if (scale.x() * scale.y() * scale.z() < 0.0) {
    for (TriangleMesh::Triangle& t : triangles) std::swap(t[1], t[2]);
  }
  std::shared_ptr<const TriangleMesh> mesh;
  try {
    mesh = std::make_shared<TriangleMesh>(std::move(vertices), std::move(triangles));
  } catch (const std::invalid_argument& e) {
    throw ConfigError(key, named + ": " + e.what());
  }
  if (!mesh->closed()) {
    warnings.push_back(key + ": mesh '" + uri + "' has " + std::to_string(mesh->boundaryEdges()) +
                       " open boundary edges: handled as a two-sided shell (no inside)");
  }
  return mesh;
}

namespace {

// The file lines of the faces tinyobjloader returns (f lines with at least 3 vertices, in order),
// counted in one pass that keeps nothing else, so the vertex count is known before the file is
// parsed. Stops (ConfigError) as soon as there are more v lines than a cloth may have particles.
std::vector<int> scanObj(std::istream& in, const std::string& key, const std::string& named) {
  std::vector<int> face_lines;
  std::string line;
  std::int64_t vertices = 0;
  int number = 0;
  while (std::getline(in, line)) {
    ++number;
    const std::size_t start = line.find_first_not_of(" \t");
    if (start == std::string::npos || start + 1 >= line.size()) continue;
    const char kind = line[start], next = line[start + 1];
    if (next != ' ' && next != '\t') continue;
    if (kind == 'v' && ++vertices > kMaxParticles) {
      throw ConfigError(key, named + " has more than " + std::to_string(kMaxParticles) +
                                 " vertices (line " + std::to_string(number) +
                                 "), the most particles a cloth may have");
    }
    if (kind == 'f') {
      std::istringstream tokens(line.substr(start + 1));
      std::string token;
      int count = 0;
      while (tokens >> token) ++count;
      if (count >= 3) face_lines.push_back(number);
    }
  }
  return face_lines;
}

}  // namespace

void loadClothMesh(SceneConfig& scene) {
  ClothConfig& cloth = scene.cloth;
  const std::string key = "cloth.mesh";
  const std::string named = "cloth mesh '" + cloth.mesh + "'";
  if (extensionOf(cloth.mesh) != "obj") {
    throw ConfigError(key, named + ": must be a Wavefront OBJ file (.obj)");
  }
  // Plain paths are scanned from the file itself; URIs (package://, file://) are read into memory
  // by resource_retriever first, as obstacle meshes are.
  std::unique_ptr<std::istream> in;
  if (isUri(cloth.mesh)) {
    in = std::make_unique<std::istringstream>(readLocation(cloth.mesh, key, "cloth mesh"));
  } else {
    std::error_code error;
    if (!std::filesystem::is_regular_file(cloth.mesh, error)) {
      throw ConfigError(key, named + " not found (or not a file)");
    }
    auto file = std::make_unique<std::ifstream>(cloth.mesh, std::ios::binary);
    if (!file->is_open()) throw ConfigError(key, named + " cannot be opened (permissions?)");
    in = std::move(file);
  }
  PolygonMesh polygons;
  polygons.source = cloth.mesh;
  polygons.face_lines = scanObj(*in, key, named);
  in->clear();
  in->seekg(0);

  tinyobj::attrib_t attrib;
  std::vector<tinyobj::shape_t> shapes;
  std::vector<tinyobj::material_t> materials;
  std::string warn, err;
  // No triangulation by the loader: faces arrive as written, so polygons are reported by face.
  // No material reader: a cloth needs none, and a missing .mtl must not stop the load.
  if (!tinyobj::LoadObj(&attrib, &shapes, &materials, &warn, &err, in.get(), nullptr, false)) {
    throw ConfigError(key, named + " does not parse: " + err);
  }
  const std::size_t count = attrib.vertices.size() / 3;
  polygons.vertices.resize(count);
  for (std::size_t v = 0; v < count; ++v) {
    polygons.vertices[v] =
        Vec3(attrib.vertices[3 * v], attrib.vertices[3 * v + 1], attrib.vertices[3 * v + 2]);
  }
  // Groups (o, g lines) become shapes in file order: their faces, concatenated, are the file's.
  for (const tinyobj::shape_t& shape : shapes) {
    for (unsigned char size : shape.mesh.num_face_vertices) polygons.face_sizes.push_back(size);
    for (const tinyobj::index_t& index : shape.mesh.indices) {
      polygons.face_indices.push_back(index.vertex_index);
    }
  }
  if (polygons.face_lines.size() != polygons.face_sizes.size()) polygons.face_lines.clear();
  cloth.mesh_data =
      std::make_shared<const ClothMesh>(makeClothMesh(polygons, key, scene.load_warnings));
}

void loadObstacleMeshes(SceneConfig& scene) {
  for (std::size_t k = 0; k < scene.obstacles.size(); ++k) {
    ObstacleConfig& o = scene.obstacles[k];
    if (o.shape != ShapeType::kMesh) continue;
    const std::string key = "obstacles[" + std::to_string(k) + "]";
    // Checked before loading: a zero factor would otherwise surface as "no triangles".
    if (!o.scale.allFinite() || (o.scale.array() == 0.0).any()) {
      std::ostringstream text;
      text << "must be 3 finite non-zero factors [sx, sy, sz] (or one), got [" << o.scale.x()
           << ", " << o.scale.y() << ", " << o.scale.z() << "]";
      throw ConfigError(key + ".scale", text.str());
    }
    o.mesh_data = loadMesh(o.mesh, o.scale, key + ".mesh", scene.load_warnings);
  }
}

std::string resolveScenePath(const std::string& location, const std::string& base_directory) {
  if (location.empty() || isUri(location) || base_directory.empty()) return location;
  const std::filesystem::path path(location);
  if (path.is_absolute()) return location;
  return (std::filesystem::path(base_directory) / path).lexically_normal().string();
}

void loadRobot(SceneConfig& scene, const std::string& urdf_xml, const std::string& source) {
  loadRobotFrom(scene, urdf_xml, source, "");
}

void loadRobotFile(SceneConfig& scene) {
  const std::string& file = scene.robot.urdf_file;
  if (file.empty()) throw ConfigError("robot.urdf_file", "is empty: no URDF file to load");
  const std::string text = readLocation(file, "robot.urdf_file", "URDF file");
  // Relative mesh paths in the URDF are relative to the URDF file (package:// is the usual form).
  std::string directory;
  if (!isUri(file)) directory = std::filesystem::path(file).parent_path().string();
  loadRobotFrom(scene, text, "robot.urdf_file '" + file + "'", directory);
}

}  // namespace pbd_cloth
