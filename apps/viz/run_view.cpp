#include "apps/viz/run_view.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "core/error.hpp"

namespace floesim::viz {

namespace {
std::string shape_text(const std::vector<std::size_t>& d) {
  std::ostringstream o;
  o << "[";
  for (std::size_t k = 0; k < d.size(); ++k) o << (k ? ", " : "") << d[k];
  o << "]";
  return o.str();
}
// Half the spacing of cell centres (a single cell: its centre, the grid starting at 0).
double half_cell(const std::vector<double>& c) { return c.size() > 1 ? 0.5 * (c[1] - c[0]) : c.empty() ? 0.0 : c[0]; }
}  // namespace

double SeaGrid::xmin() const { return x.front() - half_cell(x); }
double SeaGrid::xmax() const { return x.back() + half_cell(x); }
double SeaGrid::ymin() const { return y.front() - half_cell(y); }
double SeaGrid::ymax() const { return y.back() + half_cell(y); }

RunView::RunView(const std::string& path) : reader_(path) {
  auto fail = [&](const std::string& dataset, const std::string& what) {
    throw InputError(path + ": " + dataset + ": " + what);
  };
  auto expect = [&](const std::string& dataset, const std::vector<std::size_t>& want) {
    const auto got = reader_.shape(dataset);
    if (got != want) fail(dataset, "shape " + shape_text(got) + ", expected " + shape_text(want));
  };
  times_ = reader_.read("/time");
  // A run being written appends /time first: take the records every dataset has.
  const auto rows = [&](const std::string& d) {
    if (!reader_.has(d)) return times_.size();
    const auto shape = reader_.shape(d);
    return shape.empty() ? std::size_t{0} : shape[0];
  };
  times_.resize(std::min({times_.size(), rows("/floes/state"), rows("/sea/eta")}));
  const std::size_t T = times_.size();
  const auto off = reader_.read("/floes/offsets");
  if (off.empty() || off[0] != 0.0) fail("/floes/offsets", "expected n + 1 offsets starting at 0");
  const std::size_t n = off.size() - 1;
  const auto vshape = reader_.shape("/floes/vertices");
  if (vshape.size() != 2 || vshape[1] != 2) fail("/floes/vertices", "shape " + shape_text(vshape) + ", expected [V, 2]");
  const std::size_t V = vshape[0];
  offsets_.resize(n + 1);
  for (std::size_t i = 0; i <= n; ++i) {
    offsets_[i] = static_cast<std::size_t>(off[i]);
    if (off[i] < 0 || off[i] > static_cast<double>(V) || (i > 0 && offsets_[i] < offsets_[i - 1]))
      fail("/floes/offsets", "entry " + std::to_string(i) + " is not a non-decreasing index into /floes/vertices");
  }
  if (offsets_[n] != V) fail("/floes/offsets", "the last offset is not the vertex count " + std::to_string(V));
  body_ = reader_.read("/floes/vertices");
  {
    auto st = reader_.shape("/floes/state");
    if (!st.empty()) st[0] = std::min<std::size_t>(st[0], T);
    if (st != std::vector<std::size_t>{T, n, kStateWidth})
      fail("/floes/state", "shape " + shape_text(reader_.shape("/floes/state")) + ", expected [T, " + std::to_string(n) +
                               ", " + std::to_string(kStateWidth) + "]");
  }
  expect("/floes/static", {n});
  const auto st = reader_.read("/floes/static");
  is_static_.assign(n, 0);
  for (std::size_t i = 0; i < n; ++i) is_static_[i] = st[i] != 0.0;
  radius_.assign(n, 0.0);
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t k = offsets_[i]; k < offsets_[i + 1]; ++k)
      radius_[i] = std::max(radius_[i], std::hypot(body_x(k), body_y(k)));

  if (reader_.has("/sea/eta")) {
    sea_.x = reader_.read("/sea/x");
    sea_.y = reader_.read("/sea/y");
    const std::size_t nx = sea_.x.size(), ny = sea_.y.size();
    if (nx == 0 || ny == 0) fail("/sea/x", "the sea grid is empty");
    auto e = reader_.shape("/sea/eta");
    sea_.dims = e.size() == 2 ? 1 : 2;
    if (!e.empty()) e[0] = std::min<std::size_t>(e[0], T);
    const std::vector<std::size_t> want = sea_.dims == 1 ? std::vector<std::size_t>{T, nx} : std::vector<std::size_t>{T, ny, nx};
    if (e != want) fail("/sea/eta", "shape " + shape_text(reader_.shape("/sea/eta")) + ", expected " + shape_text(want));
  }
}

std::size_t RunView::record_at(double t) const {
  if (times_.empty()) throw InputError(path() + ": the run has no records (/time is empty)");
  const double span = times_.back() - times_.front();
  const double slack = 1e-6 * std::max(span, 1e-9);
  if (!(t >= times_.front() - slack && t <= times_.back() + slack)) {
    std::ostringstream o;
    o << path() << ": time " << t << " s is outside the run (records from " << times_.front() << " to "
      << times_.back() << " s)";
    throw InputError(o.str());
  }
  const auto it = std::lower_bound(times_.begin(), times_.end(), t);
  std::size_t k = static_cast<std::size_t>(it - times_.begin());
  if (k == times_.size() || (k > 0 && t - times_[k - 1] <= times_[k] - t)) --k;
  return k;
}

std::vector<double> RunView::state(std::size_t record) const { return reader_.read_rows("/floes/state", record, 1); }

std::vector<double> RunView::eta(std::size_t record) const {
  if (sea_.dims == 0) return {};
  return reader_.read_rows("/sea/eta", record, 1);
}

std::vector<double> RunView::state_columns(int first, int count) const {
  if (floes() == 0 || records() == 0) return {};
  return reader_.read_columns("/floes/state", static_cast<std::size_t>(first), static_cast<std::size_t>(count));
}

std::vector<double> RunView::all_eta() const {
  if (sea_.dims == 0) return {};
  return reader_.read("/sea/eta");
}

}  // namespace floesim::viz
