// Builds the particles and constraints of a scene: the rows x cols cloth grid (structural and shear
// stretch constraints, bending hinges, triangles) and the granular particles.
#pragma once

#include "pbd_cloth/config/cloth_placement.h"
#include "pbd_cloth/config/scene_config.h"
#include "pbd_cloth/model/particles.h"
#include "pbd_cloth/model/rod.h"

namespace pbd_cloth {

// Fills `particles` (cloth grid, then granular lattice) and `topology` from the scene. Pinned
// particles get inverse mass 0.
void buildScene(const SceneConfig& scene, Particles& particles, ClothTopology& topology);
// The scene's ropes as rods (model/rod.h), their particles numbered from first_particle on (the
// cloth's count), each rope's after the one before; pinned ends with inverse mass 0.
std::vector<Rod> buildRopes(const SceneConfig& scene, int first_particle);

// The bending hinges of the cloth's triangles (grid or mesh, as topology.from_mesh says), their
// rest shape taken from `rest` (the particles' build positions); replaces any hinges there are.
// buildScene calls it when cloth.bend_compliance >= 0; Simulation when bending is turned on live.
void buildBending(const Vec3Array& rest, ClothTopology& topology);

// Isometric bending hinge on edge (x0,x1) with opposite vertices x2, x3, from rest positions.
// Returns false for a degenerate (zero-area) hinge, which is then skipped.
bool makeBendConstraint(const Vec3Array& rest, int i0, int i1, int i2, int i3, BendConstraint& out);

}  // namespace pbd_cloth
