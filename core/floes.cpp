#include "core/floes.hpp"

namespace floesim {

std::vector<Vec2> Floes::world_vertices(std::size_t i) const {
  std::vector<Vec2> w;
  w.reserve(offsets[i + 1] - offsets[i]);
  for (const Vec2& p : vertices(i)) w.push_back(to_world(i, p));
  return w;
}

namespace {
FloeState initial_state(const FloeShape& shape, const FloeInput& input) {
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
  return s;
}
}  // namespace

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
  state.push_back(initial_state(shape, input));
  id.push_back(ids_issued++);
  return i;
}

void Floes::replace(std::size_t i, const FloeShape& shape, const FloeInput& input) {
  const auto first = static_cast<std::ptrdiff_t>(offsets[i]), last = static_cast<std::ptrdiff_t>(offsets[i + 1]);
  body.erase(body.begin() + first, body.begin() + last);
  body.insert(body.begin() + first, shape.body.begin(), shape.body.end());
  const std::ptrdiff_t change = static_cast<std::ptrdiff_t>(shape.body.size()) - (last - first);
  for (std::size_t k = i + 1; k < offsets.size(); ++k)
    offsets[k] = static_cast<std::size_t>(static_cast<std::ptrdiff_t>(offsets[k]) + change);
  thickness[i] = input.thickness;
  density[i] = input.density;
  area[i] = shape.props.area;
  mass[i] = shape.props.mass;
  inertia_z[i] = shape.props.inertia_z;
  inertia_x[i] = shape.props.inertia_x;
  inertia_y[i] = shape.props.inertia_y;
  ocean_drag[i] = input.ocean_drag;
  is_static[i] = input.is_static ? 1 : 0;
  state[i] = initial_state(shape, input);
  id[i] = ids_issued++;
}

Floes Floes::select(std::span<const std::size_t> which) const {
  Floes out;
  for (std::size_t i : which) {
    const auto v = vertices(i);
    out.body.insert(out.body.end(), v.begin(), v.end());
    out.offsets.push_back(out.body.size());
    out.thickness.push_back(thickness[i]);
    out.density.push_back(density[i]);
    out.area.push_back(area[i]);
    out.mass.push_back(mass[i]);
    out.inertia_z.push_back(inertia_z[i]);
    out.inertia_x.push_back(inertia_x[i]);
    out.inertia_y.push_back(inertia_y[i]);
    out.ocean_drag.push_back(ocean_drag[i]);
    out.is_static.push_back(is_static[i]);
    out.state.push_back(state[i]);
    out.id.push_back(id[i]);
  }
  out.ids_issued = ids_issued;
  return out;
}

Floes::Memory Floes::memory(std::span<const std::uint8_t> held) const {
  const std::size_t k = held_count(held, size());
  Memory m;
  for (const auto* v : {&thickness, &density, &area, &mass, &inertia_z, &inertia_x, &inertia_y, &ocean_drag})
    m.constants += per_floe_bytes(*v, k);
  m.constants += per_floe_bytes(is_static, k);
  m.constants += per_floe_bytes(id, k);
  m.vertices = csr_bytes(offsets, capacity_bytes(body), sizeof(Vec2), held);
  m.state = per_floe_bytes(state, k);
  return m;
}

}  // namespace floesim
