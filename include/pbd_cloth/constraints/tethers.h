// Long-range attachments (Kim, Chentanez, Mueller 2012): the tethers of a cloth for its current set
// of kinematic particles (the anchors), rebuilt when a gripper grasps or releases.
//
// Anchors joined by stretch links and held by the same body form a group: one pinned corner, a
// pinned edge, the patch of particles one gripper holds (two grippers holding neighbouring patches
// make two groups, as a gripper's patch beside a pin does). Each free particle gets one tether to
// the nearest anchor of each group (the shortest rest distance: on the flat grid for a grid cloth,
// along the mesh edges for a mesh), not one to every anchor: the other anchors of a group move with
// it (one gripper, one fixed edge), and the cloth's own links keep the particle's place relative to
// them. A gripper holding 6 particles used to give every particle 6 tethers, a pinned edge of 50
// particles 50, each a projection per pass (doc/journal.md, "2026-11-26: Tethers go to the nearest
// anchor of each group").
#pragma once

#include <utility>
#include <vector>

#include "pbd_cloth/model/particles.h"

namespace pbd_cloth {

class TetherBuilder {
 public:
  // Sizes the scratch for this cloth and `tethers` for `groups` groups of anchors, so that build()
  // allocates nothing (a grasp inside the step) while the anchors form no more groups than that.
  void reserve(const Particles& particles, const ClothTopology& topology, int groups,
               std::vector<Tether>& tethers);
  // The groups the cloth's kinematic particles form now. `holder`: per cloth particle, the body
  // that holds it when it is kinematic (e.g. -1 pinned, g gripper g); empty: all one body.
  int countGroups(const Particles& particles, const ClothTopology& topology,
                  const std::vector<int>& holder = {});
  // Replaces `tethers` with those of the current kinematic set, grouped by particle (as
  // Solver::projectTethers expects), each particle's in the order of their anchors. A part of a
  // mesh not connected to an anchor gets none. `spacing`: the grid's (unused for a mesh).
  void build(const Particles& particles, const ClothTopology& topology, double spacing,
             std::vector<Tether>& tethers, const std::vector<int>& holder = {});

 private:
  void findGroups(const Particles& particles, const ClothTopology& topology,
                  const std::vector<int>& holder);
  void buildGrid(const Particles& particles, const ClothTopology& topology, double spacing,
                 std::vector<Tether>& tethers);
  void buildMesh(const Particles& particles, const ClothTopology& topology,
                 std::vector<Tether>& tethers);
  // The mesh's edges as lists per particle, from topology.stretch (reserve() always; build()
  // when nothing was reserved for a cloth of this size).
  void linkEdges(const ClothTopology& topology, int n);
  // Shortest paths along the mesh edges from every anchor of `group` at once (Dijkstra with
  // several sources): the distance to the group's nearest anchor and which anchor it is.
  void groupDistances(int group, int n);

  std::vector<int> anchors_;        // the kinematic cloth particles, in index order
  std::vector<int> parent_;         // union-find over the cloth particles
  std::vector<int> group_;          // per particle: its group, -1 for a free particle
  std::vector<int> group_of_root_;  // per union-find root: its group, -1 until numbered
  int groups_ = 0;
  // Grid: the current particle's nearest anchor in each group and its distance.
  std::vector<int> nearest_;
  std::vector<double> nearest_distance_;
  // Mesh: the edges as lists per particle (CSR), and per group and particle the distance along
  // them to the group's nearest anchor and that anchor (groups_ x n, row by row).
  std::vector<int> edge_offsets_, edge_targets_, edge_fill_;
  std::vector<double> edge_lengths_;
  std::vector<double> distance_;
  std::vector<int> source_;
  std::vector<std::pair<double, int>> heap_;  // Dijkstra's queue, a binary heap
};

}  // namespace pbd_cloth
