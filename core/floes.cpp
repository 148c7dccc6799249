#include "core/floes.hpp"

namespace floesim {

std::vector<Vec2> Floes::world_vertices(std::size_t i) const {
  std::vector<Vec2> w;
  w.reserve(offsets[i + 1] - offsets[i]);
  for (const Vec2& p : vertices(i)) w.push_back(to_world(i, p));
  return w;
}

std::size_t Floes::add(const FloeShape& shape, const FloeInput& input) {
  const std::size_t i = size();
  body.insert(body.end(), shape.body.begin(), shape.body.end());
  offsets.push_back(body.size());
  thickness.push_back(input.thickness);
  density.push_back(input.density);
  area.push_back(shape.props.area);
  mass.push_back(shape.props.mass);
  inertia_z.push_back(shape.props.inertia_z);
  inertia_x.push_back(shape.props.inertia_x);
  inertia_y.push_back(shape.props.inertia_y);
  ocean_drag.push_back(input.ocean_drag);
  is_static.push_back(input.is_static ? 1 : 0);
  FloeState s;
  s.x = shape.centroid.x();
  s.y = shape.centroid.y();
  s.yaw = input.yaw;
  if (!input.is_static) {
    s.vx = input.velocity.x();
    s.vy = input.velocity.y();
    s.yaw_rate = input.angular_velocity;
    s.heave = input.heave;
    s.heave_rate = input.heave_rate;
  }
  state.push_back(s);
  return i;
}

}  // namespace floesim
