// Ropes in a scene (`ropes:`, config/rope_config.h): Cosserat rods whose particles follow the
// cloth's in the Simulation, stepped by the cloth's solver, touching its obstacles, saved and
// loaded with its state.
#include <gtest/gtest.h>

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <string>

#include "pbd_cloth/scene/scene_yaml.h"
#include "pbd_cloth/sim/simulation.h"

namespace pbd_cloth {
namespace {

SceneConfig sceneFrom(const std::string& yaml) { return sceneFromYaml(YAML::Load(yaml), "."); }

// A small cloth far away (every scene has one) and the rope given.
std::string withRope(const std::string& rope, const std::string& extra = "") {
  return "step_rate: 60\n"
         "solver: {substeps: 10, damping: 4.0}\n"
         "cloth: {rows: 2, cols: 2, spacing: 0.1, origin: [5, 5, 0], pinned: [0, 1, 2, 3]}\n"
         "ropes:\n" +
         rope + extra;
}

// The hanging chain: an inextensible, nearly limp cable of length S = 1.2 m hung by its two ends
// 2a = 1 m apart at the same height sags by c (cosh(a / c) - 1), S = 2 c sinh(a / c) (the
// catenary), within 1 % once at rest (40 segments; its bending stiffness, EI = 1.3e-6 N m^2,
// against a weight of 0.15 N over 1.2 m, changes that by far less).
TEST(Ropes, CableHungByItsEndsSagsAsTheCatenary) {
  const double a = 0.5, length = 1.2;
  // Start as a V of the cable's length: its ends at (+-a, 0, 1), its middle below.
  const int segments = 40;
  const double depth = std::sqrt(0.25 * length * length - a * a);
  std::ostringstream points;
  points << "[";
  for (int i = 0; i <= segments; ++i) {
    const double u = static_cast<double>(i) / segments;
    const double x = -a + 2.0 * a * u;
    const double z = 1.0 - depth * (1.0 - std::abs(2.0 * u - 1.0));
    points << (i ? ", " : "") << "[" << x << ", 0, " << z << "]";
  }
  points << "]";
  const SceneConfig scene = sceneFrom(withRope(
      "  - {name: cable, radius: 0.002, density: 1000, young_modulus: 1e5, shear_modulus: 4e4,\n"
      "     stretch_compliance: 0, pinned: [0, " +
      std::to_string(segments) + "], points: " + points.str() + "}\n"));
  Simulation sim(scene);
  ASSERT_EQ(sim.ropes().size(), 1u);
  const int first = sim.ropes()[0].first_particle;
  EXPECT_EQ(first, 4);  // after the cloth's 4 particles
  for (int k = 0; k < 300; ++k) sim.step();
  // The catenary's parameter c: S = 2 c sinh(a / c), by bisection (S / 2a > 1 decreases in c).
  double low = 0.01, high = 100.0;
  for (int k = 0; k < 200; ++k) {
    const double c = 0.5 * (low + high);
    (2.0 * c * std::sinh(a / c) > length ? low : high) = c;
  }
  const double c = 0.5 * (low + high);
  const double expected = c * (std::cosh(a / c) - 1.0);
  const double sag = 1.0 - sim.particles().position[first + segments / 2].z();
  double speed = 0.0;
  for (int k = 0; k <= segments; ++k) {
    speed = std::max(speed, sim.particles().velocity[first + k].norm());
  }
  std::printf("catenary: sag %.5f m, expected %.5f m (%.3f %%), fastest particle %.3g m/s\n", sag,
              expected, 100.0 * (sag - expected) / expected, speed);
  EXPECT_NEAR(sag, expected, 0.01 * expected);
  EXPECT_LT(speed, 1e-3);
}

// A rope dropped across a table-top box lies on it: after 1.5 s no particle is inside the box
// deeper than a tenth of the rope's radius, and its middle rests on the top.
TEST(Ropes, RopeDroppedOnABoxLiesOnIt) {
  const SceneConfig scene = sceneFrom(withRope(
      "  - {name: rope, start: [-0.6, 0, 0.3], end: [0.6, 0, 0.3], segments: 30, radius: 0.005,\n"
      "     young_modulus: 1e6, shear_modulus: 4e5}\n",
      "obstacles:\n"
      "  - {name: table, shape: box, size: [0.4, 0.4, 0.2], pose: [0, 0, 0.1, 0, 0, 0, 1]}\n"));
  Simulation sim(scene);
  for (int k = 0; k < 90; ++k) sim.step();
  const Rod& rope = sim.ropes()[0];
  double deepest = 0.0;
  for (int k = 0; k < rope.size(); ++k) {
    const Vec3& x = sim.particles().position[rope.first_particle + k];
    // Inside the box grown by the radius: the depth below its nearest face.
    const Vec3 inside =
        Vec3(0.2 + 0.005, 0.2 + 0.005, 0.1 + 0.005) - (x - Vec3(0, 0, 0.1)).cwiseAbs();
    if ((inside.array() > 0.0).all()) deepest = std::max(deepest, inside.minCoeff());
  }
  const double middle = sim.particles().position[rope.first_particle + 15].z();
  std::printf("rope on a box: deepest %.3g m, middle at z = %.4f m\n", deepest, middle);
  EXPECT_LT(deepest, 0.0005);
  EXPECT_NEAR(middle, 0.2 + 0.005, 0.002);
}

// Saved and loaded (through the state file's bytes), a scene with a rope continues bit for bit:
// 0.5 s, save, 0.5 s more, against a fresh simulation loaded with the saved state.
TEST(Ropes, SavedStateContinuesBitForBit) {
  const SceneConfig scene = sceneFrom(withRope(
      "  - {name: rope, start: [0, 0, 1], end: [0.8, 0, 1], segments: 20, pinned: [0]}\n"));
  Simulation straight(scene);
  for (int k = 0; k < 30; ++k) straight.step();
  SimulationState saved;
  straight.getState(saved);
  std::stringstream file;
  writeState(file, saved);
  for (int k = 0; k < 30; ++k) straight.step();

  SimulationState read;
  std::string reason;
  ASSERT_TRUE(readState(file, read, reason)) << reason;
  Simulation loaded(scene);
  ASSERT_TRUE(loaded.setState(read, reason)) << reason;
  for (int k = 0; k < 30; ++k) loaded.step();
  EXPECT_EQ(loaded.particles().position, straight.particles().position);
  EXPECT_EQ(loaded.ropes()[0].orientation, straight.ropes()[0].orientation);
  EXPECT_GT(straight.ropes()[0].angular_velocity[10].norm(), 0.0);  // it swung: there was a state
}

// A rope clamped by pinning its first two particles, inextensible: the first segment's stretch
// has no free end and no compliance (a row of nothing to solve), and the rope still hangs, finite,
// its segments at their length.
TEST(Ropes, InextensibleRopePinnedAtTwoNeighboursHangs) {
  const SceneConfig scene =
      sceneFrom(withRope("  - {name: r, start: [0, 0, 1], end: [0.5, 0, 1], segments: 10, "
                         "stretch_compliance: 0, pinned: [0, 1]}\n"));
  Simulation sim(scene);
  for (int k = 0; k < 60; ++k) sim.step();
  const Rod& rope = sim.ropes()[0];
  double worst = 0.0;
  for (int s = 0; s < rope.segments(); ++s) {
    const Vec3& a = sim.particles().position[rope.first_particle + s];
    const Vec3& b = sim.particles().position[rope.first_particle + s + 1];
    worst = std::max(worst, std::abs((b - a).norm() / rope.rest_length[s] - 1.0));
  }
  const Vec3& tip = sim.particles().position[rope.first_particle + 10];
  std::printf("rope pinned at two neighbours: tip at z = %.4f m, worst stretch %.3g\n", tip.z(),
              worst);
  ASSERT_TRUE(tip.allFinite());
  EXPECT_LT(tip.z(), 0.9);  // it hangs
  EXPECT_LT(worst, 1e-3);
}

// Refused with the key: a rope whose segments are no longer than its diameter, a pin past its
// end, no name, a rope that starts outside the bounds (its first particle out: 11 of 20, at z =
// 2.1), and ropes with the explicit springs (they are position-based rods).
TEST(Ropes, BadRopesNameTheirKey) {
  struct Case {
    std::string rope, key, says;
  };
  const Case cases[] = {
      {"{name: r, start: [0, 0, 1], end: [0.1, 0, 1], segments: 10, radius: 0.01}",
       "ropes[0].segments", "longer than the rope's diameter"},
      {"{name: r, start: [0, 0, 1], end: [1, 0, 1], segments: 10, pinned: [11]}",
       "ropes[0].pinned[0]", "out of range [0, 10]"},
      {"{start: [0, 0, 1], end: [1, 0, 1]}", "ropes[0].name", ""},
      {"{name: r, points: [[0, 0, 1]]}", "ropes[0].points", "at least 2"},
      {"{name: r, young_modulus: 0}", "ropes[0].young_modulus", "> 0"},
      {"{name: r, colour: red}", "ropes[0].colour", "unknown key"},
  };
  for (const Case& c : cases) {
    try {
      validate(sceneFrom(withRope("  - " + c.rope + "\n")));
      ADD_FAILURE() << c.rope << " was accepted";
    } catch (const ConfigError& e) {
      EXPECT_NE(std::string(e.what()).find(c.key), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(c.says), std::string::npos) << e.what();
    }
  }
  try {
    validate(sceneFrom(withRope("  - {name: r, start: [0, 0, 1], end: [0, 0, 3]}\n",
                                "bounds: {min: [-1, -1, -1], max: [6, 6, 2]}\n")));
    ADD_FAILURE() << "a rope leaving the bounds was accepted";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("ropes[0] must start inside the bounds: its particle 11"),
              std::string::npos)
        << e.what();
  }
  SceneConfig springs = sceneFrom(withRope("  - {name: r}\n"));
  springs.solver.method = Method::kMassSpring;
  EXPECT_THROW(validate(springs), ConfigError);
}

}  // namespace
}  // namespace pbd_cloth
