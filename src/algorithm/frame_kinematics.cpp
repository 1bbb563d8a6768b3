#include "featherdrive/algorithm/frame_kinematics.hpp"

#include <stdexcept>
#include <string>

namespace featherdrive {

void check_link_index(const Model& model, int link) {
  if (link < 0 || link >= model.num_links())
    throw std::invalid_argument("link index " + std::to_string(link) + " is out of range [0, " +
                                std::to_string(model.num_links()) + ")");
}

Vec3 frame_position(const Model& model, const Data& data, int link, const Vec3& point) {
  check_link_index(model, link);
  return data.world_position[link] + data.world_rotation[link] * point;
}

Vec6 frame_velocity(const Model& model, const Data& data, int link, const Vec3& point,
                    ReferenceFrame reference) {
  check_link_index(model, link);
  const Vec6& v = data.velocity[link];
  Vec6 out;
  out.head<3>() = v.head<3>();
  out.tail<3>() = v.tail<3>() + v.head<3>().cross(point);  // the point's velocity, link axes
  if (reference == ReferenceFrame::world_aligned) {
    const Mat3& R = data.world_rotation[link];
    out.head<3>() = R * out.head<3>().eval();
    out.tail<3>() = R * out.tail<3>().eval();
  }
  return out;
}

Mat3 frame_rotation(const Model& model, const Data& data, const NamedFrame& frame) {
  check_link_index(model, frame.link);
  return data.world_rotation[frame.link] * frame.rotation;
}

Vec3 frame_position(const Model& model, const Data& data, const NamedFrame& frame,
                    const Vec3& point) {
  return frame_position(model, data, frame.link, point_on_link(frame, point));
}

Vec6 frame_velocity(const Model& model, const Data& data, const NamedFrame& frame,
                    const Vec3& point, ReferenceFrame reference) {
  Vec6 v = frame_velocity(model, data, frame.link, point_on_link(frame, point), reference);
  if (reference == ReferenceFrame::local) {  // link axes -> the frame's
    v.head<3>() = frame.rotation.transpose() * v.head<3>().eval();
    v.tail<3>() = frame.rotation.transpose() * v.tail<3>().eval();
  }
  return v;
}

}  // namespace featherdrive
