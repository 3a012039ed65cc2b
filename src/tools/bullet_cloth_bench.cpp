// bullet_cloth_bench: the peer on the speed/accuracy charts. Runs the cloth of a scene YAML as a
// Bullet btSoftBody (position-based links, Bullet's own solver) and prints the same key=value line
// as cloth_bench, with the metrics computed by the same pbd_cloth functions on the same links.
// See kUsage.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <fstream>
#include <iostream>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

// Bullet's headers have unused parameters; this file is built with -Wall -Wextra.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wunused-parameter"
#include <BulletSoftBody/btDefaultSoftBodySolver.h>
#include <BulletSoftBody/btSoftBody.h>
#include <BulletSoftBody/btSoftBodyRigidBodyCollisionConfiguration.h>
#include <BulletSoftBody/btSoftRigidDynamicsWorld.h>
#include <btBulletDynamicsCommon.h>
#pragma GCC diagnostic pop

#include "bench_command_line.h"
#include "pbd_cloth/collision/collisions.h"
#include "pbd_cloth/geometry/mesh_shape.h"
#include "pbd_cloth/scene/scene_yaml.h"
#include "pbd_cloth/sim/cloth_builder.h"
#include "pbd_cloth/sim/colliders.h"
#include "pbd_cloth/sim/grippers.h"
#include "pbd_cloth/sim/metrics.h"

namespace {

const char kUsage[] =
    "Usage: bullet_cloth_bench --config <scene.yaml> --duration <s> [options]\n"
    "Builds the scene's rows x cols cloth as a Bullet btSoftBody (the particle positions, masses\n"
    "and pins of pbd_cloth::buildScene; one Bullet link per pbd_cloth stretch constraint,\n"
    "structural then shear, in the same order; pinned particles get mass 0) in a\n"
    "btSoftRigidDynamicsWorld with the scene's gravity and static obstacles, runs\n"
    "round(duration * step_rate) steps of 1/step_rate s and prints the key=value line of\n"
    "cloth_bench (wall_ms_per_step max_strain mean_strain max_penetration self_intersections\n"
    "energy finite steps ... method=bullet), the metrics computed by pbd_cloth's own functions on\n"
    "the same stretch links (final_structural_max_strain, final_structural_mean_strain: the final\n"
    "state's strain of the structural links only; last_second_median_structural_max_strain:\n"
    "the median of its max over the samples of the last second, NaN without samples or when the\n"
    "cloth blows up; median_structural_max_strain_last_1s, median_structural_mean_strain_last_1s:\n"
    "the medians over every step of the last second; every strain leaves out links between two\n"
    "pinned or held particles). A gripper that grasps at t = 0 holds its particles as moving\n"
    "pins: the particles within its radius at t = 0 get mass 0 and follow its trajectory at their\n"
    "offsets in its frame, interpolated across the internal steps of each step as pbd_cloth moves\n"
    "its held particles across the substeps. Only the Bullet step calls (and the held\n"
    "particles' moves between them) are timed. max_strain, max_penetration\n"
    "and max_self_intersections are maxima over the samples (every step for <= 5000 particles,\n"
    "every 10th otherwise, and the last step); the other metrics are those of the final state.\n"
    "\n"
    "Options (as cloth_bench):\n"
    "  --config <file>        scene YAML (the format of config/hanging.yaml)\n"
    "  --duration <s>         simulated time, >= 0\n"
    "  --set <key=value>      override a scene key (solver.substeps=20) or a Bullet knob:\n"
    "      bullet.substeps=N      internal steps per step, h = dt/N (default: solver.substeps)\n"
    "      bullet.piterations=N   position solver passes per internal step\n"
    "                             (default: solver.iterations)\n"
    "      bullet.viterations=N   velocity solver passes (default 0, Bullet's default)\n"
    "      bullet.diterations=N   drift solver passes (default 0, Bullet's default)\n"
    "      bullet.kLST=x          link stiffness in (0, 1] (default 1: inextensible)\n"
    "      bullet.kDP=x           damping per internal step in [0, 1)\n"
    "                             (default: solver.damping * h, as the pbd_cloth solver damps)\n"
    "      bullet.bending=0|1     Bullet's bending links, generateBendingConstraints(2)\n"
    "                             (default 0)\n"
    "      bullet.bend_kLST=x     stiffness of those links (default 0.5)\n"
    "  --csv <file>           t,max_strain,mean_strain,energy,max_penetration per metric sample\n"
    "  --sample-every <n>     sample the metrics every n steps\n"
    "  --positions <file>     final positions as index,x,y,z lines\n"
    "  --mesh <file.obj>      final cloth as a Wavefront OBJ\n"
    "  --quiet                no progress message on stderr\n"
    "  --help                 this text\n"
    "Bullet is built in single precision (Debian's libbullet-dev). Grasps after t = 0, releases,\n"
    "live gripper poses, granular particles, tethers and the bounds box are not simulated (a\n"
    "warning says so); cloth self-collision is\n"
    "off (Bullet needs clusters for it). A diverged cloth (max strain > 10) reports\n"
    "self_intersections=-1: not counted.\n";

constexpr int kLargeScene = 5000;  // particles; above it the metrics are sampled every 10th step
constexpr double kDivergedStrain = 10.0;  // above it self-intersections are not counted

using pbd_cloth::bench::parseCount;
using pbd_cloth::bench::parseNumber;
using pbd_cloth::bench::UsageError;

// Bullet's knobs, set with --set bullet.<name>=<value>. Negative means "from the scene".
struct BulletKnobs {
  int substeps = -1;
  int piterations = -1;
  int viterations = 0;
  int diterations = 0;
  double link_stiffness = 1.0;
  double damping = -1.0;
  bool bending = false;
  double bend_stiffness = 0.5;
};

struct Options : pbd_cloth::bench::CommonOptions {
  BulletKnobs bullet;
};

double parseFraction(const std::string& key, const std::string& text, bool zero_allowed,
                     bool one_allowed) {
  const double value = parseNumber(key, text);
  const bool above = zero_allowed ? value >= 0.0 : value > 0.0;
  const bool below = one_allowed ? value <= 1.0 : value < 1.0;
  if (!(above && below)) {
    throw UsageError(key + ": must be in " + (zero_allowed ? "[0, " : "(0, ") +
                     (one_allowed ? "1]" : "1)") + ", got " + text);
  }
  return value;
}

void setKnob(BulletKnobs& knobs, const std::string& assignment) {
  const std::size_t equals = assignment.find('=');
  const std::string key = assignment.substr(0, equals);
  const std::string value = equals == std::string::npos ? "" : assignment.substr(equals + 1);
  if (key == "bullet.substeps") {
    knobs.substeps = parseCount(key, value, 1, 100000);
  } else if (key == "bullet.piterations") {
    knobs.piterations = parseCount(key, value, 1, 100000);
  } else if (key == "bullet.viterations") {
    knobs.viterations = parseCount(key, value, 0, 100000);
  } else if (key == "bullet.diterations") {
    knobs.diterations = parseCount(key, value, 0, 100000);
  } else if (key == "bullet.kLST") {
    knobs.link_stiffness = parseFraction(key, value, false, true);
  } else if (key == "bullet.kDP") {
    knobs.damping = parseFraction(key, value, true, false);
  } else if (key == "bullet.bending") {
    knobs.bending = parseCount(key, value, 0, 1) == 1;
  } else if (key == "bullet.bend_kLST") {
    knobs.bend_stiffness = parseFraction(key, value, false, true);
  } else {
    throw UsageError("unknown Bullet knob '" + key +
                     "' (substeps, piterations, viterations, diterations, kLST, kDP, bending, "
                     "bend_kLST)");
  }
}

Options parseArguments(int argc, char** argv) {
  namespace bench = pbd_cloth::bench;
  Options options;
  bench::forEachOption(argc, argv, [&](const std::string& option, const bench::NextValue& next) {
    if (option == "--help" || option == "-h") {
      std::cout << kUsage;
      std::exit(0);
    }
    if (option == "--set") {
      const std::string assignment = next();
      if (assignment.rfind("bullet.", 0) == 0) {
        setKnob(options.bullet, assignment);
      } else {
        options.overrides.push_back(assignment);
      }
      return true;
    }
    return bench::parseCommonOption(option, next, options);
  });
  bench::requireCommonOptions(options);
  return options;
}

btVector3 toBullet(const Eigen::Vector3d& v) {
  return btVector3(static_cast<btScalar>(v.x()), static_cast<btScalar>(v.y()),
                   static_cast<btScalar>(v.z()));
}

btTransform toBullet(const pbd_cloth::Pose& pose) {
  const Eigen::Quaterniond& q = pose.orientation;
  return btTransform(btQuaternion(static_cast<btScalar>(q.x()), static_cast<btScalar>(q.y()),
                                  static_cast<btScalar>(q.z()), static_cast<btScalar>(q.w())),
                     toBullet(pose.position));
}

// Grippers that grasp at t = 0, as moving pins: the cloth particles within a gripper's radius of
// its pose at t = 0 (trajectoryPose, as pbd_cloth's Grippers::changeGrasp takes them: free
// particles, the first gripper's first) are held at their offsets in its frame. Each step they
// move from where they are to where the gripper's trajectory puts them at the step's end,
// linearly across the internal steps (the interpolation of pbd_cloth's solver across substeps).
class HeldParticles {
 public:
  // Marks the held particles kinematic (inverse mass 0: Bullet mass 0, and the strain leaves out
  // links between two of them). Returns the grippers that also grasp or release later, or grasp
  // only later: those events are not simulated.
  std::vector<std::string> grasp(const pbd_cloth::SceneConfig& scene,
                                 pbd_cloth::Particles& particles) {
    std::vector<std::string> unsupported;
    for (const pbd_cloth::GripperConfig& gripper : scene.grippers) {
      const std::vector<pbd_cloth::Waypoint>& trajectory = gripper.trajectory;
      bool at_start = false, later_events = false;
      for (const pbd_cloth::Waypoint& w : trajectory) {
        if (w.grasp < 0) continue;
        if (w.t <= 1e-9 && w.grasp == 1) {
          at_start = true;
        } else {
          later_events = true;
        }
      }
      if (later_events || !at_start) unsupported.push_back(gripper.name);
      if (!at_start) continue;
      Group group;
      group.trajectory = &trajectory;
      const pbd_cloth::Pose pose = pbd_cloth::trajectoryPose(trajectory, 0.0);
      const Eigen::Quaterniond to_local = pose.orientation.conjugate();
      for (int i = 0; i < particles.cloth_count; ++i) {
        if (particles.isKinematic(i)) continue;  // pinned, or held by an earlier gripper
        if ((particles.position[i] - pose.position).norm() > gripper.radius) continue;
        group.particles.push_back(i);
        group.offsets.push_back(to_local * (particles.position[i] - pose.position));
        particles.inverse_mass[i] = 0.0;
      }
      groups_.push_back(std::move(group));
    }
    return unsupported;
  }

  bool empty() const { return groups_.empty(); }
  int count() const {
    int n = 0;
    for (const Group& group : groups_) n += static_cast<int>(group.particles.size());
    return n;
  }

  // Where the step ending at t_end puts each held particle; from[] is where they are (the last
  // step's targets, or their start).
  void beginStep(double t_end, const pbd_cloth::Particles& particles) {
    for (Group& group : groups_) {
      const pbd_cloth::Pose pose = pbd_cloth::trajectoryPose(*group.trajectory, t_end);
      group.from.resize(group.particles.size());
      group.to.resize(group.particles.size());
      for (std::size_t k = 0; k < group.particles.size(); ++k) {
        group.from[k] = started_ ? group.to[k] : particles.position[group.particles[k]];
        group.to[k] = pose.position + pose.orientation * group.offsets[k];
      }
    }
    started_ = true;
  }

  // Before internal step s of n (h s each): each held node at its place at the step's fraction
  // s / n, with the velocity that takes it to its place at (s + 1) / n (Bullet moves every node by
  // its velocity in the prediction and leaves mass-0 nodes there).
  void place(btSoftBody* body, int s, int n, double h) const {
    const double s0 = static_cast<double>(s) / n, s1 = static_cast<double>(s + 1) / n;
    for (const Group& group : groups_) {
      for (std::size_t k = 0; k < group.particles.size(); ++k) {
        const Eigen::Vector3d x0 = (1.0 - s0) * group.from[k] + s0 * group.to[k];
        const Eigen::Vector3d x1 = (1.0 - s1) * group.from[k] + s1 * group.to[k];
        btSoftBody::Node& node = body->m_nodes[group.particles[k]];
        node.m_x = toBullet(x0);
        node.m_v = toBullet((x1 - x0) / h);
      }
    }
  }

  // After the step: each held node exactly at its target.
  void finish(btSoftBody* body) const {
    for (const Group& group : groups_) {
      for (std::size_t k = 0; k < group.particles.size(); ++k) {
        body->m_nodes[group.particles[k]].m_x = toBullet(group.to[k]);
      }
    }
  }

 private:
  struct Group {
    const std::vector<pbd_cloth::Waypoint>* trajectory = nullptr;
    std::vector<int> particles;
    std::vector<Eigen::Vector3d> offsets;  // in the gripper's frame at t = 0
    std::vector<Eigen::Vector3d> from, to;
  };
  std::vector<Group> groups_;
  bool started_ = false;
};

// A Bullet world holding the cloth and the scene's static obstacles. Members are declared in the
// order Bullet needs them built; they are destroyed in reverse.
class BulletCloth {
 public:
  BulletCloth(const pbd_cloth::SceneConfig& scene, const pbd_cloth::Particles& particles,
              const pbd_cloth::ClothTopology& topology, const BulletKnobs& knobs)
      : collision_configuration_(new btSoftBodyRigidBodyCollisionConfiguration()),
        dispatcher_(new btCollisionDispatcher(collision_configuration_.get())),
        broadphase_(new btDbvtBroadphase()),
        constraint_solver_(new btSequentialImpulseConstraintSolver()),
        soft_body_solver_(new btDefaultSoftBodySolver()),
        world_(new btSoftRigidDynamicsWorld(
            dispatcher_.get(), broadphase_.get(), constraint_solver_.get(),
            collision_configuration_.get(), soft_body_solver_.get())) {
    const btVector3 gravity = toBullet(scene.solver.gravity);
    world_->setGravity(gravity);
    btSoftBodyWorldInfo& info = world_->getWorldInfo();
    info.m_gravity = gravity;
    info.air_density = 0;  // no aerodynamics: pbd_cloth has none
    info.m_dispatcher = dispatcher_.get();
    info.m_broadphase = broadphase_.get();
    info.m_sparsesdf.Initialize();

    // Cloth particles only, in pbd_cloth's order, so node i is particle i.
    const int n = particles.cloth_count;
    std::vector<btVector3> x(n);
    std::vector<btScalar> m(n);
    for (int i = 0; i < n; ++i) {
      x[i] = toBullet(particles.position[i]);
      m[i] = particles.isKinematic(i) ? 0 : static_cast<btScalar>(particles.mass[i]);  // pin
    }
    body_ = new btSoftBody(&info, n, x.data(), m.data());
    btSoftBody::Material* material = body_->m_materials[0];
    material->m_kLST = static_cast<btScalar>(knobs.link_stiffness);
    for (const pbd_cloth::DistanceConstraint& con : topology.stretch) {
      body_->appendLink(con.i, con.j, material);
    }
    const auto& t = topology.triangles;
    for (std::size_t k = 0; k + 2 < t.size(); k += 3) {
      body_->appendFace(static_cast<int>(t[k]), static_cast<int>(t[k + 1]),
                        static_cast<int>(t[k + 2]), material);
    }
    if (knobs.bending) {
      btSoftBody::Material* bend = body_->appendMaterial();
      bend->m_kLST = static_cast<btScalar>(knobs.bend_stiffness);
      body_->generateBendingConstraints(2, bend);
    }
    const int substeps = knobs.substeps > 0 ? knobs.substeps : scene.solver.substeps;
    const double h = 1.0 / (scene.step_rate * substeps);
    btSoftBody::Config& cfg = body_->m_cfg;
    cfg.piterations = knobs.piterations > 0 ? knobs.piterations : scene.solver.iterations;
    cfg.viterations = knobs.viterations;
    cfg.diterations = knobs.diterations;
    // Bullet scales velocities by (1 - kDP) once per internal step; pbd_cloth by (1 - damping h).
    cfg.kDP = static_cast<btScalar>(
        knobs.damping >= 0.0 ? knobs.damping : std::min(0.99, scene.solver.damping * h));
    cfg.kDF = static_cast<btScalar>(scene.cloth.friction.kinetic_coefficient);
    body_->getCollisionShape()->setMargin(static_cast<btScalar>(scene.cloth.thickness));
    world_->addSoftBody(body_);
    addObstacles(scene);
  }

  ~BulletCloth() {
    for (int k = world_->getNumCollisionObjects() - 1; k >= 0; --k) {
      btCollisionObject* object = world_->getCollisionObjectArray()[k];
      if (btSoftBody* soft = btSoftBody::upcast(object)) {
        world_->removeSoftBody(soft);
      } else if (btRigidBody* rigid = btRigidBody::upcast(object)) {
        world_->removeRigidBody(rigid);
      }
      delete object;
    }
  }

  btSoftBody* body() { return body_; }

  // One internal Bullet step of h s. stepSimulation(h, 0) takes exactly one internal step; N of
  // them are the same as stepSimulation(dt, N, dt / N) without its single-precision time
  // accumulator, which can run N - 1 or N + 1 internal steps in a frame.
  void internalStep(btScalar h) { world_->stepSimulation(h, 0); }

  // Copies node positions and velocities into the cloth particles of `particles`.
  void read(pbd_cloth::Particles& particles) const {
    const btSoftBody::tNodeArray& nodes = body_->m_nodes;
    for (int i = 0; i < nodes.size(); ++i) {
      const btVector3& x = nodes[i].m_x;
      const btVector3& v = nodes[i].m_v;
      particles.position[i] = pbd_cloth::Vec3(x.x(), x.y(), x.z());
      particles.velocity[i] = pbd_cloth::Vec3(v.x(), v.y(), v.z());
    }
  }

  int linkCount() const { return body_->m_links.size(); }

 private:
  void addObstacles(const pbd_cloth::SceneConfig& scene) {
    for (const pbd_cloth::ObstacleConfig& obstacle : scene.obstacles) {
      btCollisionShape* shape = nullptr;
      btTransform pose = toBullet(obstacle.pose);
      switch (obstacle.shape) {
        case pbd_cloth::ShapeType::kSphere:
          shape = new btSphereShape(static_cast<btScalar>(obstacle.radius));
          break;
        case pbd_cloth::ShapeType::kBox:
          shape = new btBoxShape(toBullet(0.5 * obstacle.size));
          break;
        case pbd_cloth::ShapeType::kCapsule:
          shape = new btCapsuleShapeZ(static_cast<btScalar>(obstacle.radius),
                                      static_cast<btScalar>(obstacle.length));
          break;
        case pbd_cloth::ShapeType::kPlane: {
          const Eigen::Vector3d normal = obstacle.normal.normalized();
          shape = new btStaticPlaneShape(
              toBullet(normal), static_cast<btScalar>(obstacle.offset / obstacle.normal.norm()));
          pose.setIdentity();
          break;
        }
        case pbd_cloth::ShapeType::kCylinder:
          shape = new btCylinderShapeZ(btVector3(static_cast<btScalar>(obstacle.radius),
                                                 static_cast<btScalar>(obstacle.radius),
                                                 static_cast<btScalar>(0.5 * obstacle.length)));
          break;
        case pbd_cloth::ShapeType::kMesh: {
          // A static concave mesh: Bullet's own BVH over the same (welded, scaled) triangles.
          auto mesh = std::make_unique<btTriangleMesh>();
          const auto& vertices = obstacle.mesh_data->vertices();
          for (const auto& triangle : obstacle.mesh_data->triangles()) {
            mesh->addTriangle(toBullet(vertices[triangle[0]]), toBullet(vertices[triangle[1]]),
                              toBullet(vertices[triangle[2]]));
          }
          shape = new btBvhTriangleMeshShape(mesh.get(), true);
          meshes_.push_back(std::move(mesh));
          break;
        }
      }
      shapes_.emplace_back(shape);
      btRigidBody::btRigidBodyConstructionInfo info(0, nullptr, shape);
      info.m_startWorldTransform = pose;
      info.m_friction = static_cast<btScalar>(scene.cloth.friction.kinetic_coefficient);
      world_->addRigidBody(new btRigidBody(info));
    }
  }

  std::vector<std::unique_ptr<btTriangleMesh>> meshes_;  // kept alive for their shapes
  std::unique_ptr<btSoftBodyRigidBodyCollisionConfiguration> collision_configuration_;
  std::unique_ptr<btCollisionDispatcher> dispatcher_;
  std::unique_ptr<btBroadphaseInterface> broadphase_;
  std::unique_ptr<btSequentialImpulseConstraintSolver> constraint_solver_;
  std::unique_ptr<btSoftBodySolver> soft_body_solver_;
  std::unique_ptr<btSoftRigidDynamicsWorld> world_;
  std::vector<std::unique_ptr<btCollisionShape>> shapes_;
  btSoftBody* body_ = nullptr;  // owned by the world's object list, deleted in the destructor
};

// The metrics of Simulation::computeMetrics, on particles filled from Bullet's nodes.
pbd_cloth::Metrics computeMetrics(const pbd_cloth::SceneConfig& scene,
                                  const pbd_cloth::Particles& particles,
                                  const pbd_cloth::ClothTopology& topology,
                                  const pbd_cloth::Collisions& collisions) {
  pbd_cloth::Metrics metrics;
  pbd_cloth::computeStrain(particles, topology, metrics.max_strain, metrics.mean_strain);
  pbd_cloth::computeStructuralStrain(particles, topology, metrics.structural_max_strain,
                                     metrics.structural_mean_strain);
  metrics.max_penetration = collisions.maxPenetration(particles, topology);
  metrics.finite = pbd_cloth::allFinite(particles);
  // A diverged cloth (links ten times their length) puts every triangle in one grid cell of the
  // intersection count, which then takes minutes and means nothing: -1 = not counted.
  metrics.self_intersections = metrics.finite && metrics.max_strain < kDivergedStrain
                                   ? pbd_cloth::countSelfIntersections(particles, topology)
                                   : -1;
  const Eigen::Vector3d& g = scene.solver.gravity;
  for (int i = 0; i < particles.size(); ++i) {
    if (particles.isKinematic(i)) continue;
    metrics.kinetic_energy += 0.5 * particles.mass[i] * particles.velocity[i].squaredNorm();
    metrics.potential_energy -= particles.mass[i] * g.dot(particles.position[i]);
  }
  metrics.energy = metrics.kinetic_energy + metrics.potential_energy;
  return metrics;
}

void warnAboutUnsupported(const pbd_cloth::SceneConfig& scene) {
  if (scene.granular.count > 0) {
    std::cerr << "bullet_cloth_bench: warning: granular particles are not simulated\n";
  }
  if (scene.bounds.enabled) {
    std::cerr << "bullet_cloth_bench: warning: the bounds box is not simulated\n";
  }
  if (scene.cloth.self_collision) {
    std::cerr << "bullet_cloth_bench: warning: cloth self-collision is off in Bullet\n";
  }
  if (scene.cloth.tethers) {
    std::cerr << "bullet_cloth_bench: warning: cloth.tethers: Bullet's cloth has no tethers\n";
  }
}

int run(const Options& options) {
  pbd_cloth::SceneConfig scene = pbd_cloth::bench::loadScene(options);
  scene.granular.count = 0;  // the cloth only: Bullet's node i is pbd_cloth's particle i
  if (!options.quiet) warnAboutUnsupported(scene);

  std::ofstream csv = pbd_cloth::bench::openOutput("--csv", options.csv);
  std::ofstream positions = pbd_cloth::bench::openOutput("--positions", options.positions);
  std::ofstream mesh = pbd_cloth::bench::openOutput("--mesh", options.mesh);
  pbd_cloth::bench::writeCsvHeader(csv);

  pbd_cloth::Particles particles;
  pbd_cloth::ClothTopology topology;
  pbd_cloth::buildScene(scene, particles, topology);
  // Grippers grasping at t = 0: their particles become mass-0 nodes that follow the trajectory.
  HeldParticles held;
  for (const std::string& name : held.grasp(scene, particles)) {
    if (!options.quiet) {
      std::cerr << "bullet_cloth_bench: warning: gripper '" << name
                << "': only a grasp at t = 0 is simulated (its particles as moving pins); its "
                   "other grasp and release events are not\n";
    }
  }
  pbd_cloth::Collisions collisions;  // only for maxPenetration against the same obstacles
  collisions.configure(collisionSettings(scene));
  collisions.prepare(particles, topology);
  BulletCloth cloth(scene, particles, topology, options.bullet);

  const int substeps =
      options.bullet.substeps > 0 ? options.bullet.substeps : scene.solver.substeps;
  const int piterations =
      options.bullet.piterations > 0 ? options.bullet.piterations : scene.solver.iterations;
  const double dt = 1.0 / scene.step_rate;
  const btScalar h = static_cast<btScalar>(dt / substeps);
  const double step_count = options.duration * scene.step_rate;
  if (step_count > std::numeric_limits<int>::max()) {
    throw UsageError("--duration: " + std::to_string(step_count) + " steps are too many");
  }
  const long long steps = std::llround(step_count);
  const int particle_count = particles.size();
  const int sample_every =
      options.sample_every > 0 ? options.sample_every : (particle_count <= kLargeScene ? 1 : 10);
  if (!options.quiet) {
    std::cerr << "bullet_cloth_bench: " << options.config << ": " << particle_count << " nodes, "
              << cloth.linkCount() << " links, " << steps << " steps of " << dt << " s, "
              << substeps << " internal steps x " << piterations << " position passes\n";
  }

  pbd_cloth::bench::LastSecondStrain last_second(steps, scene.step_rate, sample_every);
  pbd_cloth::bench::LastSecondStepStrain last_second_steps(steps, scene.step_rate);
  pbd_cloth::Metrics last = computeMetrics(scene, particles, topology, collisions);
  double max_strain = last.max_strain;
  double max_penetration = last.max_penetration;
  int max_self_intersections = last.self_intersections;
  pbd_cloth::bench::writeCsvRow(csv, 0.0, last);

  using Clock = std::chrono::steady_clock;
  double step_seconds = 0.0;
  std::clock_t step_cpu = 0;
  long long done = 0;
  while (done < steps) {
    const Clock::time_point begin = Clock::now();
    const std::clock_t cpu_begin = std::clock();
    if (held.empty()) {
      for (int s = 0; s < substeps; ++s) cloth.internalStep(h);
    } else {
      held.beginStep((done + 1) * dt, particles);
      for (int s = 0; s < substeps; ++s) {
        held.place(cloth.body(), s, substeps, h);
        cloth.internalStep(h);
      }
      held.finish(cloth.body());
    }
    step_cpu += std::clock() - cpu_begin;
    step_seconds += std::chrono::duration<double>(Clock::now() - begin).count();
    ++done;
    if (last_second_steps.counts(done)) {
      cloth.read(particles);
      double structural_max = 0.0, structural_mean = 0.0;
      pbd_cloth::computeStructuralStrain(particles, topology, structural_max, structural_mean);
      last_second_steps.add(structural_max, structural_mean);
    }
    if (done % sample_every != 0 && done != steps) continue;
    cloth.read(particles);
    last = computeMetrics(scene, particles, topology, collisions);
    max_strain = std::max(max_strain, last.max_strain);
    max_penetration = std::max(max_penetration, last.max_penetration);
    max_self_intersections = std::max(max_self_intersections, last.self_intersections);
    pbd_cloth::bench::writeCsvRow(csv, done * dt, last);
    last_second.add(done, last);
    if (!last.finite) break;
  }
  cloth.read(particles);

  if (positions.is_open()) {
    for (int i = 0; i < particles.size(); ++i) {
      const pbd_cloth::Vec3& x = particles.position[i];
      positions << i << ',' << x.x() << ',' << x.y() << ',' << x.z() << '\n';
    }
  }
  if (mesh.is_open()) {
    mesh << "# bullet_cloth_bench " << topology.rows << " x " << topology.cols
         << " cloth at t = " << done * dt << " s\n";
    for (int i = 0; i < particles.cloth_count; ++i) {
      const pbd_cloth::Vec3& x = particles.position[i];
      mesh << "v " << x.x() << ' ' << x.y() << ' ' << x.z() << '\n';
    }
    const std::vector<unsigned>& t = topology.triangles;
    for (std::size_t k = 0; k + 2 < t.size(); k += 3) {
      mesh << "f " << t[k] + 1 << ' ' << t[k + 1] + 1 << ' ' << t[k + 2] + 1 << '\n';
    }
  }
  pbd_cloth::bench::finishOutput(csv, options.csv);
  pbd_cloth::bench::finishOutput(positions, options.positions);
  pbd_cloth::bench::finishOutput(mesh, options.mesh);

  const double per_step = done > 0 ? 1.0 / static_cast<double>(done) : 0.0;
  const BulletKnobs& knobs = options.bullet;
  std::printf(
      "wall_ms_per_step=%.6g max_strain=%.9g mean_strain=%.9g max_penetration=%.9g "
      "self_intersections=%d energy=%.9g finite=%d steps=%lld sim_time=%.9g "
      "iterations_per_step=%d method=bullet substeps=%d iterations=%d particles=%d "
      "max_self_intersections=%d sample_every=%d bullet_links=%d bullet_viterations=%d "
      "bullet_diterations=%d bullet_kLST=%g bullet_bending=%d final_structural_max_strain=%.9g "
      "final_structural_mean_strain=%.9g cpu_ms_per_step=%.6g "
      "last_second_median_structural_max_strain=%.9g median_structural_max_strain_last_1s=%.9g "
      "median_structural_mean_strain_last_1s=%.9g grasped_particles=%d\n",
      1e3 * step_seconds * per_step, max_strain, last.mean_strain, max_penetration,
      last.self_intersections, last.energy, last.finite ? 1 : 0, done, done * dt,
      substeps * piterations, substeps, piterations, particle_count, max_self_intersections,
      sample_every, cloth.linkCount(), knobs.viterations, knobs.diterations, knobs.link_stiffness,
      knobs.bending ? 1 : 0, last.structural_max_strain, last.structural_mean_strain,
      1e3 * static_cast<double>(step_cpu) / CLOCKS_PER_SEC * per_step, last_second.median(),
      last_second_steps.medianMax(), last_second_steps.medianMean(), held.count());
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  return pbd_cloth::bench::runTool("bullet_cloth_bench",
                                   [&] { return run(parseArguments(argc, argv)); });
}
