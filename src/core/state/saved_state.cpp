#include "pbd_cloth/state/saved_state.h"

#include <cstring>
#include <fstream>
#include <iterator>

namespace pbd_cloth {

namespace {

constexpr char kStateMagic[8] = {'P', 'B', 'D', 'S', 'T', 'A', 'T', 'E'};
constexpr char kSolverDataMagic[8] = {'P', 'B', 'D', 'S', 'O', 'L', 'V', 'R'};

// Appends numbers as their bytes: a double goes in and comes out with every bit.
class ByteWriter {
 public:
  explicit ByteWriter(std::vector<std::uint8_t>& out) : out_(out) {}

  // Resized and copied into, not insert()ed: GCC 12 warns falsely about inserting a range.
  void bytes(const void* data, std::size_t size) {
    const std::size_t at = out_.size();
    out_.resize(at + size);
    if (size > 0) std::memcpy(out_.data() + at, data, size);
  }
  template <class T>
  void raw(const T& value) {
    bytes(&value, sizeof(T));
  }
  void count(std::size_t n) { raw(static_cast<std::uint64_t>(n)); }
  void flag(bool value) { raw(static_cast<std::uint8_t>(value ? 1 : 0)); }
  void index(int value) { raw(static_cast<std::int32_t>(value)); }
  void vec(const Vec3& v) {
    raw(v.x());
    raw(v.y());
    raw(v.z());
  }
  void pose(const Pose& p) {
    vec(p.position);
    raw(p.orientation.x());
    raw(p.orientation.y());
    raw(p.orientation.z());
    raw(p.orientation.w());
  }
  void text(const std::string& s) {
    count(s.size());
    bytes(s.data(), s.size());
  }
  void vecs(const Vec3Array& values) {
    count(values.size());
    for (const Vec3& v : values) vec(v);
  }

 private:
  std::vector<std::uint8_t>& out_;
};

// Reads what ByteWriter wrote; every read checks that the bytes are there, and every count that
// the bytes left could hold that many items, so a truncated or corrupt file fails with a reason
// instead of allocating gigabytes.
class ByteReader {
 public:
  ByteReader(const std::uint8_t* data, std::size_t size) : data_(data), size_(size) {}

  bool ok() const { return error_.empty(); }
  const std::string& error() const { return error_; }
  void fail(const std::string& what) {
    if (error_.empty()) error_ = what;
  }

  template <class T>
  T raw(const char* what) {
    T value{};
    if (!ok()) return value;
    if (size_ - offset_ < sizeof(T)) {
      fail(std::string("truncated at ") + what + " (byte " + std::to_string(offset_) + ")");
      return value;
    }
    std::memcpy(&value, data_ + offset_, sizeof(T));
    offset_ += sizeof(T);
    return value;
  }
  // A count of items of at least `item_bytes` each.
  std::size_t count(const char* what, std::size_t item_bytes) {
    const std::uint64_t n = raw<std::uint64_t>(what);
    if (ok() && item_bytes > 0 && n > (size_ - offset_) / item_bytes) {
      fail(std::string(what) + ": " + std::to_string(n) + " items do not fit in the " +
           std::to_string(size_ - offset_) + " bytes left");
      return 0;
    }
    return ok() ? static_cast<std::size_t>(n) : 0;
  }
  bool flag(const char* what) { return raw<std::uint8_t>(what) != 0; }
  int index(const char* what) { return raw<std::int32_t>(what); }
  Vec3 vec(const char* what) {
    const double x = raw<double>(what), y = raw<double>(what), z = raw<double>(what);
    return Vec3(x, y, z);
  }
  Pose pose(const char* what) {
    Pose p;
    p.position = vec(what);
    const double x = raw<double>(what), y = raw<double>(what), z = raw<double>(what),
                 w = raw<double>(what);
    p.orientation = Eigen::Quaterniond(w, x, y, z);
    return p;
  }
  std::string text(const char* what) {
    const std::size_t n = count(what, 1);
    if (!ok()) return std::string();
    std::string s(reinterpret_cast<const char*>(data_ + offset_), n);
    offset_ += n;
    return s;
  }
  Vec3Array vecs(const char* what) {
    Vec3Array values(count(what, 3 * sizeof(double)));
    for (Vec3& v : values) v = vec(what);
    return values;
  }
  // The version found (after header()).
  std::uint32_t version() const { return version_; }
  bool header(const char (&magic)[8], const char* kind) {
    if (size_ < sizeof(magic) || std::memcmp(data_, magic, sizeof(magic)) != 0) {
      fail(std::string("not a ") + kind + " (no '" + std::string(magic, sizeof(magic)) +
           "' header)");
      return false;
    }
    offset_ = sizeof(magic);
    version_ = raw<std::uint32_t>("version");
    if (ok() && (version_ < kOldestStateFileVersion || version_ > kStateFileVersion)) {
      fail(std::string(kind) + " version " + std::to_string(version_) + ", this build reads " +
           std::to_string(kOldestStateFileVersion) + " to " + std::to_string(kStateFileVersion));
    }
    return ok();
  }
  bool atEnd() {
    if (ok() && offset_ != size_) {
      fail(std::to_string(size_ - offset_) + " bytes after the end of the state");
    }
    return ok();
  }

 private:
  const std::uint8_t* data_;
  std::size_t size_;
  std::size_t offset_ = 0;
  std::uint32_t version_ = 0;
  std::string error_;
};

void writeBody(ByteWriter& w, const BodySnapshot& body) {
  w.text(body.name);
  w.pose(body.pose);
  w.pose(body.target);
  w.flag(body.enabled);
  w.flag(body.live);
  w.flag(body.jump_to_target);
}

BodySnapshot readBody(ByteReader& r) {
  BodySnapshot body;
  body.name = r.text("body name");
  body.pose = r.pose("body pose");
  body.target = r.pose("body target");
  body.enabled = r.flag("body enabled");
  body.live = r.flag("body live");
  body.jump_to_target = r.flag("body jump_to_target");
  return body;
}

// The smallest a body takes in the file: for the plausibility check of a count.
constexpr std::size_t kMinBodyBytes = 8 + 2 * 7 * sizeof(double) + 3;

void writeSolverPart(ByteWriter& w, const SimulationState& state) {
  w.vecs(state.substep_start);
  w.count(state.mesh_contacts.size());
  for (const MeshContactCache& c : state.mesh_contacts) {
    w.index(c.particle);
    w.index(c.collider);
    w.index(c.triangle);
    w.raw(c.distance);
    w.vec(c.point);
  }
  w.index(state.search_window);
  w.index(state.chosen_substeps);
  w.index(state.calm_steps);
  w.count(state.rope_orientations.size());
  for (double value : state.rope_orientations) w.raw(value);
  w.vecs(state.rope_angular_velocities);
}

void readSolverPart(ByteReader& r, SimulationState& state) {
  state.substep_start = r.vecs("substep_start");
  state.mesh_contacts.resize(r.count("mesh_contacts", 3 * 4 + 4 * sizeof(double)));
  for (MeshContactCache& c : state.mesh_contacts) {
    c.particle = r.index("mesh contact particle");
    c.collider = r.index("mesh contact collider");
    c.triangle = r.index("mesh contact triangle");
    c.distance = r.raw<double>("mesh contact distance");
    c.point = r.vec("mesh contact point");
  }
  if (r.version() >= 2) state.search_window = r.index("search_window");
  if (r.version() >= 3) {
    state.chosen_substeps = r.index("chosen_substeps");
    state.calm_steps = r.index("calm_steps");
  }
  if (r.version() >= 4) {
    state.rope_orientations.resize(r.count("rope_orientations", sizeof(double)));
    for (double& value : state.rope_orientations) value = r.raw<double>("rope orientation");
    state.rope_angular_velocities = r.vecs("rope_angular_velocities");
  }
}

std::vector<std::uint8_t> encodeState(const SimulationState& state) {
  std::vector<std::uint8_t> bytes;
  ByteWriter w(bytes);
  w.bytes(kStateMagic, sizeof(kStateMagic));
  w.raw(kStateFileVersion);
  w.raw(state.time);
  w.vecs(state.position);
  w.vecs(state.velocity);
  w.count(state.grippers.size());
  for (const GripperSnapshot& g : state.grippers) {
    w.text(g.name);
    w.pose(g.pose);
    w.pose(g.target);
    w.flag(g.live);
    w.count(g.grasped.size());
    for (int i : g.grasped) w.index(i);
    w.vecs(g.grasp_offsets);
    w.vec(g.velocity);
    w.count(g.next_waypoint);
  }
  w.count(state.colliders.size());
  for (const BodySnapshot& body : state.colliders) writeBody(w, body);
  w.count(state.robot_links.size());
  for (const BodySnapshot& body : state.robot_links) writeBody(w, body);
  writeSolverPart(w, state);
  return bytes;
}

bool decodeState(const std::uint8_t* data, std::size_t size, SimulationState& state,
                 std::string& reason) {
  ByteReader r(data, size);
  SimulationState read;
  if (r.header(kStateMagic, "pbd_cloth state file")) {
    read.time = r.raw<double>("time");
    read.position = r.vecs("positions");
    read.velocity = r.vecs("velocities");
    read.grippers.resize(r.count("grippers", 8 + 2 * 7 * sizeof(double)));
    for (GripperSnapshot& g : read.grippers) {
      g.name = r.text("gripper name");
      g.pose = r.pose("gripper pose");
      g.target = r.pose("gripper target");
      g.live = r.flag("gripper live");
      g.grasped.resize(r.count("gripper grasped", 4));
      for (int& i : g.grasped) i = r.index("gripper grasped");
      g.grasp_offsets = r.vecs("gripper grasp_offsets");
      g.velocity = r.vec("gripper velocity");
      g.next_waypoint = static_cast<std::size_t>(r.raw<std::uint64_t>("gripper next_waypoint"));
    }
    read.colliders.resize(r.count("colliders", kMinBodyBytes));
    for (BodySnapshot& body : read.colliders) body = readBody(r);
    read.robot_links.resize(r.count("robot_links", kMinBodyBytes));
    for (BodySnapshot& body : read.robot_links) body = readBody(r);
    readSolverPart(r, read);
    r.atEnd();
  }
  if (!r.ok()) {
    reason = r.error();
    return false;
  }
  state = std::move(read);
  return true;
}

}  // namespace

void writeState(std::ostream& out, const SimulationState& state) {
  const std::vector<std::uint8_t> bytes = encodeState(state);
  out.write(reinterpret_cast<const char*>(bytes.data()),
            static_cast<std::streamsize>(bytes.size()));
}

bool readState(std::istream& in, SimulationState& state, std::string& reason) {
  const std::vector<std::uint8_t> bytes((std::istreambuf_iterator<char>(in)),
                                        std::istreambuf_iterator<char>());
  return decodeState(bytes.data(), bytes.size(), state, reason);
}

bool writeStateFile(const std::string& path, const SimulationState& state, std::string& reason) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  if (!out) {
    reason = "cannot write '" + path + "'";
    return false;
  }
  writeState(out, state);
  out.close();
  if (!out) {
    reason = "writing '" + path + "' failed";
    return false;
  }
  return true;
}

bool readStateFile(const std::string& path, SimulationState& state, std::string& reason) {
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    reason = "cannot read '" + path + "'";
    return false;
  }
  if (!readState(in, state, reason)) {
    reason = "'" + path + "': " + reason;
    return false;
  }
  return true;
}

std::vector<std::uint8_t> encodeSolverData(const SimulationState& state) {
  std::vector<std::uint8_t> bytes;
  ByteWriter w(bytes);
  w.bytes(kSolverDataMagic, sizeof(kSolverDataMagic));
  w.raw(kStateFileVersion);
  writeSolverPart(w, state);
  return bytes;
}

bool decodeSolverData(const std::vector<std::uint8_t>& data, SimulationState& state,
                      std::string& reason) {
  ByteReader r(data.data(), data.size());
  SimulationState read;
  if (r.header(kSolverDataMagic, "pbd_cloth solver_data")) {
    readSolverPart(r, read);
    r.atEnd();
  }
  if (!r.ok()) {
    reason = "solver_data: " + r.error();
    return false;
  }
  state.substep_start = std::move(read.substep_start);
  state.mesh_contacts = std::move(read.mesh_contacts);
  state.search_window = read.search_window;
  state.chosen_substeps = read.chosen_substeps;
  state.calm_steps = read.calm_steps;
  state.rope_orientations = std::move(read.rope_orientations);
  state.rope_angular_velocities = std::move(read.rope_angular_velocities);
  return true;
}

}  // namespace pbd_cloth
