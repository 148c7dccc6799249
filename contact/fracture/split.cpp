#include "contact/fracture/split.hpp"

#include "core/error.hpp"

namespace floesim::fracture {

std::optional<SplitPlan> plan_split(const Floes& floes, std::size_t i, const Chord& chord, double gap,
                                    double min_area) {
  if (floes.is_static[i]) return std::nullopt;
  const auto outline = floes.vertices(i);
  double size = 0.0;
  for (const Vec2& p : outline) size = std::max(size, p.norm());
  const auto polygons = split_polygon(outline, chord, 1e-9 * size);
  if (!polygons) return std::nullopt;
  SplitPlan plan;
  plan.thickness = floes.thickness[i];
  plan.density = floes.density[i];
  plan.ocean_drag = floes.ocean_drag[i];
  for (int k = 0; k < 2; ++k) {
    FloeInput in;
    in.vertices = (*polygons)[static_cast<std::size_t>(k)];
    in.thickness = plan.thickness;
    in.density = plan.density;
    in.origin = "a piece of a split floe";
    try {
      plan.shapes[static_cast<std::size_t>(k)] = make_floe_shape(in);
    } catch (const InputError&) {
      return std::nullopt;  // degenerate piece
    }
    if (plan.shapes[static_cast<std::size_t>(k)].props.area < min_area) return std::nullopt;
    plan.centroid[static_cast<std::size_t>(k)] = plan.shapes[static_cast<std::size_t>(k)].centroid;
  }
  const Vec2 d = (chord.to - chord.from).normalized();
  plan.normal = Vec2{-d.y(), d.x()};
  if (plan.normal.dot(plan.centroid[1] - plan.centroid[0]) < 0.0) plan.normal = -plan.normal;
  const double m0 = plan.shapes[0].props.mass, m1 = plan.shapes[1].props.mass;
  plan.centroid[0] -= gap * m1 / (m0 + m1) * plan.normal;
  plan.centroid[1] += gap * m0 / (m0 + m1) * plan.normal;
  return plan;
}

std::array<FloeState, 2> piece_states(const SplitPlan& plan, const FloeState& parent, double parent_inertia_z) {
  const Vec2 g{parent.x, parent.y};
  std::array<Vec2, 2> r;
  double inertia = 0.0;
  for (int k = 0; k < 2; ++k) {
    const auto ks = static_cast<std::size_t>(k);
    r[ks] = rotate(plan.centroid[ks], parent.yaw);
    inertia += plan.shapes[ks].props.inertia_z + plan.shapes[ks].props.mass * r[ks].squaredNorm();
  }
  const double omega = parent.yaw_rate * parent_inertia_z / inertia;
  std::array<FloeState, 2> out;
  for (int k = 0; k < 2; ++k) {
    const auto ks = static_cast<std::size_t>(k);
    FloeState& s = out[ks];
    s = parent;
    s.x = g.x() + r[ks].x();
    s.y = g.y() + r[ks].y();
    s.vx = parent.vx - omega * r[ks].y();
    s.vy = parent.vy + omega * r[ks].x();
    s.yaw_rate = omega;
    // The parent's bottom plane z = heave + (pitch, roll) . (x - G) at the new centroid.
    s.heave = parent.heave + parent.pitch * r[ks].x() + parent.roll * r[ks].y();
    s.heave_rate = parent.heave_rate + parent.pitch_rate * r[ks].x() + parent.roll_rate * r[ks].y();
  }
  return out;
}

std::size_t apply_split(Floes& floes, std::size_t i, const SplitPlan& plan, const std::array<FloeState, 2>& states) {
  std::size_t index[2] = {i, 0};
  for (int k = 0; k < 2; ++k) {
    const auto ks = static_cast<std::size_t>(k);
    FloeShape shape = plan.shapes[ks];
    shape.centroid = Vec2{states[ks].x, states[ks].y};
    FloeInput in;
    in.thickness = plan.thickness;
    in.density = plan.density;
    in.ocean_drag = plan.ocean_drag;
    in.yaw = states[ks].yaw;
    if (k == 0) floes.replace(i, shape, in);
    else index[1] = floes.add(shape, in);
    floes.state[index[ks]] = states[ks];
  }
  return index[1];
}

}  // namespace floesim::fracture
