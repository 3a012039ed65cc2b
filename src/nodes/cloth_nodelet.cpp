// pbd_cloth/ClothNodelet: the same ClothRos as cloth_node, inside a nodelet manager, so a consumer
// in the same manager receives ~state without serialisation.
#include <memory>

#include <nodelet/exception.h>
#include <nodelet/nodelet.h>
#include <pluginlib/class_list_macros.hpp>

#include "pbd_cloth/ros/cloth_ros.h"

namespace pbd_cloth {

class ClothNodelet : public nodelet::Nodelet {
 private:
  void onInit() override {
    try {
      cloth_ = std::make_unique<ClothRos>(getNodeHandle(), getPrivateNodeHandle());
    } catch (const ConfigError& error) {
      // Fail the load (the manager reports it to `nodelet load`) rather than run a wrong scene.
      throw nodelet::Exception(error.what());
    }
  }

  std::unique_ptr<ClothRos> cloth_;
};

}  // namespace pbd_cloth

PLUGINLIB_EXPORT_CLASS(pbd_cloth::ClothNodelet, nodelet::Nodelet)
