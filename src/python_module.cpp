// spinning_top._core: the Python module over the ROS-free core (issue 11). Thin on purpose: no
// physics here. Every configuration goes through parse_scene_config, the validation the YAML
// files and the node use, so a bad key is refused with the core's message; states come back as
// numpy arrays. python/spinning_top/__init__.py re-exports this and documents the API.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <variant>
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
    const std::string name = py::cast<std::string>(key);
    try {
      values[name] = value_text(value);
    } catch (const py::error_already_set&) {
      // e.g. a numpy array of two values, whose __float__ raises: name the key (issue 19).
      throw InvalidParameter(name, "a " + brief_text(py::str(value.attr("__class__").attr("__name__"))) +
                                       " is not a number or a name");
    }
  }
  return values;
}

void write3(const Eigen::Vector3d& x, double* values) { std::copy(x.data(), x.data() + 3, values); }

/// A state's fields as the module shows them, after its time, in order: the columns of
/// Simulator.run (one row per time asked for) and the keys of Simulator.snapshot().
struct StateField {
  const char* name;
  py::ssize_t width;  ///< 1: a number; 3 or 4: a vector
  void (*write)(const Snapshot& s, double* values);
};
const StateField kStateFields[] = {
    {"attitude", 4,
     [](const Snapshot& s, double* v) {
       v[0] = s.attitude.w(), v[1] = s.attitude.x(), v[2] = s.attitude.y(), v[3] = s.attitude.z();
     }},
    {"body_rates", 3, [](const Snapshot& s, double* v) { write3(s.body_rates, v); }},
    {"tilt", 1, [](const Snapshot& s, double* v) { *v = tilt_of(s.attitude); }},
    {"normal_force", 1, [](const Snapshot& s, double* v) { *v = s.outputs.normal_force; }},
    {"contact_force", 3, [](const Snapshot& s, double* v) { write3(s.outputs.contact_force, v); }},
    {"center_of_mass", 3, [](const Snapshot& s, double* v) { write3(s.outputs.center_of_mass, v); }},
    {"center_of_mass_velocity", 3, [](const Snapshot& s, double* v) { write3(s.outputs.center_of_mass_velocity, v); }},
    {"contact_point", 3, [](const Snapshot& s, double* v) { write3(s.outputs.contact_point, v); }},
    {"energy", 1, [](const Snapshot& s, double* v) { *v = s.outputs.energy; }},
    {"friction_work", 1, [](const Snapshot& s, double* v) { *v = s.outputs.dissipated_energy; }},
    // The tip's height above the floor (simulate's pz): 0 in contact, > 0 in flight (HYBRID.md).
    {"tip_height", 1, [](const Snapshot& s, double* v) { *v = s.outputs.contact_point.z(); }},
};

/// Texts as a numpy array of str (dtype '<U…'), so that rows can be picked by comparison
/// (run["phase"] == "flight"); an empty list still gives a str array.
py::array text_column(const std::vector<const char*>& texts) {
  py::list list;
  for (const char* text : texts) list.append(py::str(text));
  return py::module::import("numpy").attr("array")(list, py::arg("dtype") = "str");
}

py::dict snapshot_dict(const Snapshot& s) {
  py::dict d;
  d["time"] = s.time;
  for (const StateField& field : kStateFields) {
    double values[4];
    field.write(s, values);
    if (field.width == 1)
      d[field.name] = values[0];
    else
      d[field.name] = py::array_t<double>(field.width, values);
  }
  d["phase"] = to_string(s.phase);
  // The snapshot's alone: Simulator.run has no column for it.
  d["vertical_angular_momentum"] = s.outputs.vertical_angular_momentum;
  return d;
}

/// A time as a message shows it (6 significant digits).
std::string brief_time(double t) {
  char text[32];
  std::snprintf(text, sizeof text, "%.6g", t);
  return text;
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

/// The trajectory at `times` (increasing), as simulate writes it: a row at each time asked for, and
/// one at each transition of the hybrid model (lift_off, take_off, landing) at its own time; stops
/// at the first terminal event, whose row has the event's time. Columns of equal length: the
/// state's fields, "phase" and "events" (simulate's phase and event columns, numpy arrays of str);
/// "event" (one str) is the terminal event or "".
/// A column of numbers from Python (a list, an array), or ValueError naming it (`what`).
py::array_t<double, py::array::c_style | py::array::forcecast> numbers(const py::handle& values, const std::string& what) {
  py::array_t<double, py::array::c_style | py::array::forcecast> array;
  try {
    array = py::array_t<double, py::array::c_style | py::array::forcecast>(py::reinterpret_borrow<py::object>(values));
  } catch (const py::error_already_set& e) {
    throw py::value_error(what + ": must be numbers (" + brief_text(e.what(), 80) + ")");
  }
  if (array.ndim() != 1)
    throw py::value_error(what + ": must be one-dimensional, got " + std::to_string(array.ndim()) + " dimensions");
  return array;
}

py::dict run_trajectory(Simulator& simulator, const py::object& times_given, double max_steps) {
  checked_max_steps(max_steps);
  const auto times = numbers(times_given, "times");
  const auto t = times.unchecked<1>();
  const py::ssize_t n = t.shape(0);
  for (py::ssize_t i = 1; i < n; ++i)
    if (!(t(i) > t(i - 1))) throw py::value_error("times must be increasing");
  if (n > 0 && std::isfinite(t(n - 1)) && t(n - 1) > kMaxSimulatedTime)
    throw py::value_error("times: at most 1e9 s (32 years; beyond it the state loses its meaning), got " +
                          brief_time(t(n - 1)));
  // A row is the state at its time: a time the run has passed has no state to show.
  if (n > 0 && !(t(0) >= simulator.time()))
    throw py::value_error("times must start at or after the simulator's time (" + exact_text(simulator.time()) + " s)");
  std::vector<double> time;
  std::vector<std::vector<double>> fields(std::size(kStateFields));  // kStateFields' columns, row after row
  std::vector<const char*> phases, events;                           // to_string's static texts
  SampledRun sampled;
  {
    py::gil_scoped_release release;
    // Transitions that earlier advance_to calls passed and nobody took are before these rows.
    simulator.take_transitions();
    sampled = sample_run(simulator, n, [&](long long i) { return t(i); }, max_steps, StateWhereStepsRunOut::kDrop,
                         [&](double row_time, const Snapshot& s, Event event) {
                           time.push_back(row_time);
                           phases.push_back(to_string(s.phase));
                           events.push_back(to_string(event));
                           for (std::size_t k = 0; k < fields.size(); ++k) {
                             fields[k].resize(fields[k].size() + kStateFields[k].width);
                             kStateFields[k].write(s, fields[k].data() + fields[k].size() - kStateFields[k].width);
                           }
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
  for (std::size_t k = 0; k < fields.size(); ++k) d[kStateFields[k].name] = column(fields[k], kStateFields[k].width);
  d["phase"] = text_column(phases);
  d["events"] = text_column(events);
  d["event"] = std::string(to_string(sampled.event));
  return d;
}

std::string outcome_name(const CaseOutcome& o) {
  if (o.out_of_steps) return "out_of_steps";
  return o.event == Event::kNone ? "none" : to_string(o.event);
}

/// A case as run_cases reports it: its outcome, or the core's refusal.
struct CaseResult {
  std::optional<CaseOutcome> outcome;  ///< empty: the core refused the case
  std::string refusal;                 ///< the core's message, for a refused case
};

/// A case's value in one column: a number, a flag or a text.
using CaseValue = std::variant<double, bool, std::string>;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

/// run_cases' columns, in order: its dict's keys, each case's values and what each holds (the
/// unit first), which the sweep shows (sweep.OUTCOME_COLUMNS, from outcome_columns()). A refused
/// case: outcome "refused" and the core's message; NaN in every number, false, "" elsewhere.
struct OutcomeColumn {
  const char* name;
  const char* description;
  double CaseOutcome::*number = nullptr;              ///< a number's member of the outcome; NaN if refused
  CaseValue (*value)(const CaseResult& r) = nullptr;  ///< the other columns' value

  CaseValue of(const CaseResult& r) const {
    if (number == nullptr) return value(r);
    return r.outcome ? (*r.outcome).*number : kNaN;
  }
};
const OutcomeColumn kOutcomeColumns[] = {
    {"outcome",
     "the terminal event: none (ran to the duration; hops do not end a run), lift_off (the run cannot fly on: "
     "after_lift_off stop, or a pivot whose free tip would not rise), fallen, energy_drift, non_finite; or "
     "out_of_steps, refused",
     nullptr,
     [](const CaseResult& r) -> CaseValue { return r.outcome ? outcome_name(*r.outcome) : std::string("refused"); }},
    {"event_time", "[s] time of the event, empty if none", nullptr,
     [](const CaseResult& r) -> CaseValue {
       return r.outcome && r.outcome->event != Event::kNone ? r.outcome->end_time : kNaN;
     }},
    {"end_time", "[s] the duration, the event's time, or where max_steps ran out", &CaseOutcome::end_time},
    {"min_normal_force", "[N] least R over the run (exact: closed form; time-steppers, and runs whose tip left the floor: the samples)",
     &CaseOutcome::min_normal_force},
    {"max_tilt", "[rad] largest angle of the axis from the vertical (likewise)", &CaseOutcome::max_tilt},
    {"final_tilt", "[rad] at end_time", &CaseOutcome::final_tilt},
    {"final_energy", "[J] E at end_time", &CaseOutcome::final_energy},
    {"friction_work", "[J] energy dissipated by end_time: work against friction (viscous) and the landings' losses",
     &CaseOutcome::friction_work},
    {"energy_balance_error", "max |B - B0| / (|B0| + m g h), B = E - C wZ^2/2 + W (exact: at the end)",
     &CaseOutcome::energy_balance_error},
    {"lift_offs", "lift_off transitions after which the run went on (0 with after_lift_off stop)", nullptr,
     [](const CaseResult& r) -> CaseValue { return r.outcome ? static_cast<double>(r.outcome->lift_offs) : kNaN; }},
    {"landings", "landings of the tip from the air", nullptr,
     [](const CaseResult& r) -> CaseValue { return r.outcome ? static_cast<double>(r.outcome->landings) : kNaN; }},
    {"first_lift_off_time", "[s] the first lift_off, a transition or the terminal event; empty if none", nullptr,
     [](const CaseResult& r) -> CaseValue {
       return r.outcome && r.outcome->first_lift_off_time >= 0.0 ? r.outcome->first_lift_off_time : kNaN;
     }},
    {"max_hop_height", "[m] the highest the tip rose above the floor (0: it never left it)",
     &CaseOutcome::max_hop_height},
    {"method", "the integrator that ran (auto's choice)", nullptr,
     [](const CaseResult& r) -> CaseValue { return std::string(r.outcome ? to_string(r.outcome->method) : ""); }},
    {"fallback", "auto ran its fallback (exact refused the state)", nullptr,
     [](const CaseResult& r) -> CaseValue { return r.outcome && r.outcome->fallback; }},
    {"steps", "integration steps taken (exact: requests)", nullptr,
     [](const CaseResult& r) -> CaseValue { return r.outcome ? static_cast<double>(r.outcome->steps) : kNaN; }},
    {"message", "why the core refused the case (outcome refused)", nullptr,
     [](const CaseResult& r) -> CaseValue { return r.refusal; }},
};

/// A column's values as Python has them: numbers and flags as numpy arrays, texts as a list.
py::object column_object(const std::vector<CaseValue>& values) {
  const py::ssize_t n = static_cast<py::ssize_t>(values.size());
  if (!values.empty() && std::holds_alternative<std::string>(values.front())) {
    std::vector<std::string> texts;
    for (const CaseValue& v : values) texts.push_back(std::get<std::string>(v));
    return py::cast(texts);
  }
  if (!values.empty() && std::holds_alternative<bool>(values.front())) {
    py::array_t<bool> flags(n);
    for (py::ssize_t i = 0; i < n; ++i) flags.mutable_data()[i] = std::get<bool>(values[i]);
    return std::move(flags);
  }
  py::array_t<double> numbers(n);
  for (py::ssize_t i = 0; i < n; ++i) numbers.mutable_data()[i] = std::get<double>(values[i]);
  return std::move(numbers);
}

/// Cases base + (key = columns[key][i]) for i = 0..n-1, run without the GIL: one row each in
/// kOutcomeColumns, a case the core refuses too.
py::dict run_cases(const py::dict& base, const py::dict& columns, const CaseSettings& settings) {
  validate(settings);
  const ParameterMap base_values = to_parameter_map(base);
  std::vector<std::string> keys;
  std::vector<py::array_t<double, py::array::c_style | py::array::forcecast>> arrays;
  py::ssize_t n = -1;
  for (const auto& [key, values] : columns) {
    keys.push_back(py::cast<std::string>(key));
    arrays.push_back(numbers(values, brief_text(keys.back())));
    if (n >= 0 && arrays.back().shape(0) != n) throw py::value_error("columns differ in length");
    n = arrays.back().shape(0);
  }
  if (n == 0) throw py::value_error(brief_text(keys.front()) + ": no values (a column needs at least one case)");
  if (n < 0) n = 1;  // no column: the base case alone
  const std::size_t count = static_cast<std::size_t>(n);
  std::vector<const double*> data;
  for (const auto& a : arrays) data.push_back(a.data());

  std::vector<CaseResult> results(count);
  {
    py::gil_scoped_release release;
    ParameterMap values = base_values;
    for (std::size_t i = 0; i < count; ++i) {
      for (std::size_t k = 0; k < keys.size(); ++k) values[keys[k]] = exact_text(data[k][i]);
      try {
        results[i].outcome = run_case(parse_scene_config(values, /*require_all=*/false), settings);
      } catch (const InvalidParameter& e) {
        results[i].refusal = e.what();
      }
    }
  }
  py::dict d;
  for (const OutcomeColumn& column : kOutcomeColumns) {
    std::vector<CaseValue> values;
    for (const CaseResult& result : results) values.push_back(column.of(result));
    d[column.name] = column_object(values);
  }
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
  m.def("outcome_columns", [] {
    std::vector<std::pair<std::string, std::string>> columns;
    for (const OutcomeColumn& column : kOutcomeColumns) columns.emplace_back(column.name, column.description);
    return columns;
  });

  py::class_<Simulator>(m, "Simulator")
      .def(py::init([](const py::dict& keys, bool require_all) {
             return make_simulator(parse_scene_config(to_parameter_map(keys), require_all));
           }),
           py::arg("keys"), py::arg("require_all") = false)
      .def(
          "advance_to",
          [](Simulator& s, double t, double max_steps) {
            checked_max_steps(max_steps);
            // Time only moves forward: an earlier t did nothing and said nothing (issue 19). (A
            // non-finite t: the core refuses it.)
            if (std::isfinite(t) && t > kMaxSimulatedTime)
              throw py::value_error("advance_to: t must be at most 1e9 s (32 years; beyond it the state loses its "
                                    "meaning), got " + brief_time(t));
            if (t < s.time())
              throw py::value_error("advance_to: t = " + brief_time(t) + " s is before the simulator's time " +
                                    brief_time(s.time()) + " s; it only moves forward (reset() starts again)");
            Event event;
            {
              py::gil_scoped_release release;
              event = s.advance_to(t, WorkBudget::steps_left(max_steps, s.work()));
            }
            return std::string(to_string(event));
          },
          py::arg("t"), py::arg("max_steps") = std::numeric_limits<double>::infinity())
      .def("run", &run_trajectory, py::arg("times"), py::arg("max_steps") = std::numeric_limits<double>::infinity(),
           "The trajectory as simulate writes it: a row at each of `times` (increasing, from time on) and one "
           "at each transition (lift_off, take_off, landing) at its own time; the run stops at its first "
           "terminal event, whose row has the event's time. A dict of columns: time, the state's fields "
           "(attitude N x 4 w x y z, body_rates, tilt, normal_force, contact_force, center_of_mass and its "
           "velocity, contact_point (the tip P), energy, friction_work (friction and impacts), tip_height), "
           "phase and events (numpy arrays of str: simulate's phase and event columns), and event (str): "
           "the terminal event or ''.")
      .def("snapshot", [](const Simulator& s) { return snapshot_dict(s.snapshot()); },
           "The state now: run()'s fields at time (phase a str), and vertical_angular_momentum.")
      .def(
          "take_transitions",
          [](Simulator& s) {
            py::list taken;
            for (const Transition& transition : s.take_transitions())
              taken.append(py::make_tuple(std::string(to_string(transition.event)), snapshot_dict(transition.state)));
            return taken;
          },
          "The transitions (lift_off, take_off, landing) that advance_to passed since the last call, in time "
          "order: [(event, snapshot at its time)]. run() shows them as rows instead.")
      .def(
          "hops",
          [](const Simulator& s) {
            const HopSummary hops = s.hops();
            py::dict d;
            d["lift_offs"] = hops.lift_offs;
            d["take_offs"] = hops.take_offs;
            d["landings"] = hops.landings;
            d["first_lift_off_time"] = hops.first_lift_off_time >= 0.0 ? hops.first_lift_off_time : kNaN;
            d["max_hop_height"] = hops.max_hop_height;
            d["impact_loss"] = hops.impact_loss;
            return d;
          },
          "The hops so far: counts of lift_off, take_off and landing transitions, the first lift-off's time "
          "(nan: none), the highest the tip rose [m], the kinetic energy lost in landings [J].")
      .def("reset", &Simulator::reset)
      .def_property_readonly("phase", [](const Simulator& s) { return std::string(to_string(s.phase())); })
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
