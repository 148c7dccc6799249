// Run files (core/run_file.hpp) from Python without h5py: the summary, any
// numeric dataset as a NumPy array of its shape, and the comparison that
// `floesim compare` and `floesim regress` make.
#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#include <string>

#include "core/run_file.hpp"
#include "python/bindings.hpp"

namespace py = pybind11;

namespace floesim::python {

void bind_run_file(py::module_& m) {
  m.def(
      "read_run_info",
      [](const std::string& path) {
        const RunInfo r = read_run_info(path);
        py::dict d;
        d["format"] = r.format;
        d["status"] = r.status;
        d["config"] = r.config;
        d["records"] = r.records;
        d["floes"] = r.floes;
        d["vertices"] = r.vertices;
        d["t_first"] = r.t_first;
        d["t_last"] = r.t_last;
        d["checkpoint_time"] = r.checkpoint_time >= 0.0 ? py::object(py::float_(r.checkpoint_time)) : py::object(py::none());
        d["energy_columns"] = r.energy_columns;
        py::dict shapes;
        for (const auto& [name, shape] : r.datasets) shapes[py::str(name)] = py::tuple(py::cast(shape));
        d["datasets"] = shapes;
        return d;
      },
      py::arg("path"), "A run file's summary: format, status, config, records, floes, datasets (path: shape).");
  m.def(
      "read_dataset",
      [](const std::string& path, const std::string& dataset) {
        RunDataset r = read_run_dataset(path, dataset);
        std::vector<py::ssize_t> shape(r.shape.begin(), r.shape.end());
        py::array_t<double> a(shape);
        std::copy(r.values.begin(), r.values.end(), a.mutable_data());
        return py::make_tuple(a, r.columns);
      },
      py::arg("path"), py::arg("dataset"),
      "One dataset as (array of its shape, float64; its `columns` attribute or []).");
  m.def(
      "compare_runs",
      [](const std::string& a, const std::string& b, double rtol, double atol) {
        const CompareResult r = compare_runs(a, b, {rtol, atol});
        py::list diffs;
        for (const DatasetDifference& x : r.differences) {
          py::dict d;
          d["dataset"] = x.dataset;
          d["what"] = x.what;
          d["count"] = x.count;
          d["max_abs"] = x.max_abs;
          d["at"] = x.at;
          diffs.append(d);
        }
        py::dict d;
        d["equal"] = r.equal();
        d["datasets_compared"] = r.datasets_compared;
        d["differences"] = diffs;
        return d;
      },
      py::arg("a"), py::arg("b"), py::arg("rtol") = CompareOptions{}.rtol, py::arg("atol") = CompareOptions{}.atol,
      "Compares run A with reference B as `floesim compare` does: equal when |a - b| <= atol + rtol |b|.");
}

}  // namespace floesim::python
