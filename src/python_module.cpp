// spinning_top._core: the Python module over the ROS-free core (issue 11). Thin on purpose: no
// physics here. Every configuration goes through parse_scene_config, the validation the YAML
// files and the node use, so a bad key is refused with the core's message; states come back as
// numpy arrays. python/spinning_top/__init__.py re-exports this and documents the API.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "spinning_top/case_run.hpp"
#include "spinning_top/config.hpp"
#include "spinning_top/scene_file.hpp"
#include "spinning_top/simulator.hpp"

namespace py = pybind11;

namespace spinning_top {
namespace {

/// A number as text that parses back to the same double (17 significant digits).
std::string exact_text(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.17g", value);
  return text;
}

/// A Python value as the text a YAML file or --set would give: floats with 17 digits (so the
/// double that reaches the core is the caller's, bit for bit), ints and strings as written.
std::string value_text(const py::handle& value) {
  if (py::isinstance<py::bool_>(value)) return py::cast<bool>(value) ? "true" : "false";  // refused by the core, naming the key
  if (py::isinstance<py::float_>(value)) return exact_text(py::cast<double>(value));
  if (py::isinstance<py::str>(value)) return py::cast<std::string>(value);
  // ints, numpy scalars: Python's own str() is exact for integers; other numbers go through float.
  if (py::isinstance<py::int_>(value)) return py::str(value);
  if (py::hasattr(value, "__float__")) return exact_text(py::cast<double>(value.attr("__float__")()));
  return py::str(value);
}

ParameterMap to_parameter_map(const py::dict& keys) {
  ParameterMap values;
  for (const auto& [key, value] : keys) {
    if (!py::isinstance<py::str>(key)) throw py::type_error("configuration keys are strings, e.g. 'initial/spin'");
    values[py::cast<std::string>(key)] = value_text(value);
  }
  return values;
}

py::array_t<double> vector_array(const Eigen::Vector3d& v) { return py::array_t<double>(3, v.data()); }

py::dict snapshot_dict(const Snapshot& s) {
  py::dict d;
  const Quaternion& q = s.attitude;
  const double wxyz[4] = {q.w(), q.x(), q.y(), q.z()};
  d["time"] = s.time;
  d["attitude"] = py::array_t<double>(4, wxyz);
  d["body_rates"] = vector_array(s.body_rates);
  d["tilt"] = tilt_of(q);
  d["normal_force"] = s.outputs.normal_force;
  d["contact_force"] = vector_array(s.outputs.contact_force);
  d["center_of_mass"] = vector_array(s.outputs.center_of_mass);
  d["center_of_mass_velocity"] = vector_array(s.outputs.center_of_mass_velocity);
  d["contact_point"] = vector_array(s.outputs.contact_point);
  d["energy"] = s.outputs.energy;
  d["vertical_angular_momentum"] = s.outputs.vertical_angular_momentum;
  d["friction_work"] = s.outputs.dissipated_energy;
  return d;
}

/// A run's step allowance from Python: a whole number >= 1, or inf (the default) for no limit.
double checked_max_steps(double max_steps) {
  if (!(max_steps >= 1.0 && (max_steps == std::floor(max_steps) || std::isinf(max_steps))))
    throw py::value_error("max_steps: must be a whole number >= 1, or inf for no limit, got " + exact_text(max_steps));
  return max_steps;
}

class StepBudgetExceeded : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// The trajectory at `times` (increasing), as simulate writes it: stops at the first event,
/// whose row has the event's time. Columns of equal length; "event" names the event or is "".
py::dict run_trajectory(Simulator& simulator, const py::array_t<double, py::array::c_style | py::array::forcecast>& times,
                        double max_steps) {
  checked_max_steps(max_steps);
  const auto t = times.unchecked<1>();
  const py::ssize_t n = t.shape(0);
  for (py::ssize_t i = 1; i < n; ++i)
    if (!(t(i) > t(i - 1))) throw py::value_error("times must be increasing");
  // A row is the state at its time: a time the run has passed has no state to show.
  if (n > 0 && !(t(0) >= simulator.time()))
    throw py::value_error("times must start at or after the simulator's time (" + exact_text(simulator.time()) + " s)");
  std::vector<double> time, attitude, rates, com, com_velocity, contact, contact_force, normal_force, energy, work, tilt;
  auto push3 = [](std::vector<double>& v, const Eigen::Vector3d& x) { v.insert(v.end(), x.data(), x.data() + 3); };
  SampledRun sampled;
  {
    py::gil_scoped_release release;
    sampled = sample_run(simulator, n, [&](long long i) { return t(i); }, max_steps, StateWhereStepsRunOut::kDrop,
                         [&](double row_time, const Snapshot& s, Event) {
                           time.push_back(row_time);
                           const Quaternion& q = s.attitude;
                           attitude.insert(attitude.end(), {q.w(), q.x(), q.y(), q.z()});
                           push3(rates, s.body_rates);
                           push3(com, s.outputs.center_of_mass);
                           push3(com_velocity, s.outputs.center_of_mass_velocity);
                           push3(contact, s.outputs.contact_point);
                           push3(contact_force, s.outputs.contact_force);
                           normal_force.push_back(s.outputs.normal_force);
                           energy.push_back(s.outputs.energy);
                           work.push_back(s.outputs.dissipated_energy);
                           tilt.push_back(tilt_of(q));
                         });
  }
  if (sampled.out_of_steps)
    throw StepBudgetExceeded("the run needs more than max_steps " + exact_text(max_steps) + " integration steps (at t = " +
                             exact_text(simulator.time()) + " s) with " + simulator.integrator_description());
  const py::ssize_t rows = static_cast<py::ssize_t>(time.size());
  auto column = [rows](std::vector<double>& v, py::ssize_t width) {
    if (width == 1) return py::array_t<double>(rows, v.data());
    return py::array_t<double>({rows, width}, v.data());
  };
  py::dict d;
  d["time"] = column(time, 1);
  d["attitude"] = column(attitude, 4);
  d["body_rates"] = column(rates, 3);
  d["tilt"] = column(tilt, 1);
  d["normal_force"] = column(normal_force, 1);
  d["contact_force"] = column(contact_force, 3);
  d["center_of_mass"] = column(com, 3);
  d["center_of_mass_velocity"] = column(com_velocity, 3);
  d["contact_point"] = column(contact, 3);
  d["energy"] = column(energy, 1);
  d["friction_work"] = column(work, 1);
  d["event"] = std::string(to_string(sampled.event));
  return d;
}

const char* outcome_name(const CaseOutcome& o) {
  if (o.out_of_steps) return "out_of_steps";
  return o.event == Event::kNone ? "none" : to_string(o.event);
}

/// Cases base + (key = columns[key][i]) for i = 0..n-1, run without the GIL. A case the core
/// refuses is a row with outcome "refused" and the core's message; every other column NaN.
py::dict run_cases(const py::dict& base, const py::dict& columns, const CaseSettings& settings) {
  validate(settings);
  const ParameterMap base_values = to_parameter_map(base);
  std::vector<std::string> keys;
  std::vector<py::array_t<double, py::array::c_style | py::array::forcecast>> arrays;
  py::ssize_t n = -1;
  for (const auto& [key, values] : columns) {
    keys.push_back(py::cast<std::string>(key));
    arrays.emplace_back(py::reinterpret_borrow<py::object>(values));
    if (arrays.back().ndim() != 1) throw py::value_error("column '" + keys.back() + "' is not one-dimensional");
    if (n >= 0 && arrays.back().shape(0) != n) throw py::value_error("columns differ in length");
    n = arrays.back().shape(0);
  }
  if (n < 0) n = 1;  // no column: the base case alone
  const std::size_t count = static_cast<std::size_t>(n);
  std::vector<const double*> data;
  for (const auto& a : arrays) data.push_back(a.data());

  const double nan = std::numeric_limits<double>::quiet_NaN();
  py::array_t<double> end_time(n), event_time(n), min_r(n), max_tilt(n), final_tilt(n), energy(n), work(n), balance(n), steps(n);
  py::array_t<bool> fallback(n);
  double* columns_out[] = {end_time.mutable_data(), event_time.mutable_data(), min_r.mutable_data(), max_tilt.mutable_data(),
                           final_tilt.mutable_data(), energy.mutable_data(), work.mutable_data(), balance.mutable_data(),
                           steps.mutable_data()};
  bool* fallback_out = fallback.mutable_data();
  std::vector<std::string> outcome(count), method(count), message(count);
  {
    py::gil_scoped_release release;
    ParameterMap values = base_values;
    for (std::size_t i = 0; i < count; ++i) {
      for (std::size_t k = 0; k < keys.size(); ++k) values[keys[k]] = exact_text(data[k][i]);
      try {
        const CaseOutcome o = run_case(parse_scene_config(values, /*require_all=*/false), settings);
        const double row[] = {o.end_time, o.event == Event::kNone ? nan : o.end_time, o.min_normal_force, o.max_tilt,
                              o.final_tilt, o.final_energy, o.friction_work, o.energy_balance_error,
                              static_cast<double>(o.steps)};
        for (std::size_t c = 0; c < 9; ++c) columns_out[c][i] = row[c];
        fallback_out[i] = o.fallback;
        outcome[i] = outcome_name(o);
        method[i] = to_string(o.method);
      } catch (const InvalidParameter& e) {
        for (double* c : columns_out) c[i] = nan;
        fallback_out[i] = false;
        outcome[i] = "refused";
        message[i] = e.what();
      }
    }
  }
  py::dict d;
  d["outcome"] = outcome;
  d["event_time"] = event_time;
  d["end_time"] = end_time;
  d["min_normal_force"] = min_r;
  d["max_tilt"] = max_tilt;
  d["final_tilt"] = final_tilt;
  d["final_energy"] = energy;
  d["friction_work"] = work;
  d["energy_balance_error"] = balance;
  d["method"] = method;
  d["fallback"] = fallback;
  d["steps"] = steps;
  d["message"] = message;
  return d;
}

}  // namespace
}  // namespace spinning_top

PYBIND11_MODULE(_core, m) {
  using namespace spinning_top;
  m.doc() = "The spinning_top core (C++): simulator, configuration keys, case runner. Use the spinning_top package.";

  static py::exception<InvalidParameter> invalid_parameter(m, "InvalidParameter", PyExc_ValueError);
  py::register_exception<SceneFileError>(m, "SceneFileError", PyExc_ValueError);
  py::register_exception<StepBudgetExceeded>(m, "StepBudgetExceeded", PyExc_RuntimeError);
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const InvalidParameter& e) {
      // The key as an attribute, so that a caller can tell which value to fix.
      py::object error = py::reinterpret_borrow<py::object>(invalid_parameter)(e.what());
      error.attr("key") = e.parameter();
      PyErr_SetObject(invalid_parameter.ptr(), error.ptr());
    }
  });

  m.def("parameter_specs", [] {
    py::list specs;
    for (const ParameterSpec& s : parameter_specs()) {
      py::dict d;
      d["key"] = s.key;
      d["unit"] = s.unit;
      d["default"] = s.default_value;
      d["required_in_file"] = s.required_in_file;
      d["description"] = s.description;
      specs.append(d);
    }
    return specs;
  });
  m.def("read_scene_file", &read_scene_file, py::arg("path"));
  m.def(
      "validate",
      [](const py::dict& keys, bool require_all) { parse_scene_config(to_parameter_map(keys), require_all); },
      py::arg("keys"), py::arg("require_all") = false);

  py::class_<CaseSettings>(m, "CaseSettings")
      .def(py::init([](double duration, double sample_rate, double max_steps) {
             CaseSettings s{duration, sample_rate, max_steps};
             validate(s);
             return s;
           }),
           py::arg("duration") = CaseSettings{}.duration, py::arg("sample_rate") = CaseSettings{}.sample_rate,
           py::arg("max_steps") = CaseSettings{}.max_steps)
      .def_readonly("duration", &CaseSettings::duration)
      .def_readonly("sample_rate", &CaseSettings::sample_rate)
      .def_readonly("max_steps", &CaseSettings::max_steps);
  m.def("run_cases", &run_cases, py::arg("base"), py::arg("columns"), py::arg("settings"));

  py::class_<Simulator>(m, "Simulator")
      .def(py::init([](const py::dict& keys, bool require_all) {
             return make_simulator(parse_scene_config(to_parameter_map(keys), require_all));
           }),
           py::arg("keys"), py::arg("require_all") = false)
      .def(
          "advance_to",
          [](Simulator& s, double t, double max_steps) {
            checked_max_steps(max_steps);
            Event event;
            {
              py::gil_scoped_release release;
              event = s.advance_to(t, WorkBudget::steps_left(max_steps, s.steps()));
            }
            return std::string(to_string(event));
          },
          py::arg("t"), py::arg("max_steps") = std::numeric_limits<double>::infinity())
      .def("run", &run_trajectory, py::arg("times"), py::arg("max_steps") = std::numeric_limits<double>::infinity())
      .def("snapshot", [](const Simulator& s) { return snapshot_dict(s.snapshot()); })
      .def("reset", &Simulator::reset)
      .def_property_readonly("time", &Simulator::time)
      .def_property_readonly("event", [](const Simulator& s) { return std::string(to_string(s.event())); })
      .def_property_readonly("steps", &Simulator::steps)
      .def("integrator_description", &Simulator::integrator_description)
      .def("integrator_choice", [](const Simulator& s) {
        const IntegratorChoice c = s.integrator_choice();
        py::dict d;
        d["configured"] = to_string(c.configured);
        d["method"] = to_string(c.method);
        d["fallback"] = c.fallback;
        d["reason"] = c.reason;
        return d;
      });
}
