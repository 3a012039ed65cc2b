// The kinds of collision shape (shapes.h), shared by the scene description (obstacles[i].shape)
// and the runtime shapes.
#pragma once

namespace pbd_cloth {

enum class ShapeType { kSphere, kBox, kCapsule, kPlane, kCylinder, kMesh };

}  // namespace pbd_cloth
