#include "io/machine/machine_file.h"

#include <tinyxml2.h>

#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <sstream>

#include "core/model/effects.h"
#include "core/numerics/quantities.h"
#include "core/numerics/units.h"
#include "io/common/io_error.h"
#include "io/common/text_util.h"

namespace tolver {
namespace {

using tinyxml2::XMLElement;

class Reader {
 public:
  explicit Reader(std::string file) : file_(std::move(file)) {}

  [[noreturn]] void fail(const XMLElement* e, const std::string& field, const std::string& msg) {
    throw InputError(file_, e ? e->GetLineNum() : 0, 0, field, msg);
  }

  std::string attr(const XMLElement* e, const char* name, bool required = true,
                   const char* def = "") {
    const char* v = e->Attribute(name);
    if (!v) {
      if (required) fail(e, std::string(e->Name()) + "." + name, "missing attribute");
      return def;
    }
    return v;
  }

  std::vector<double> numbers(const XMLElement* e, const char* name, size_t count,
                              bool required = true) {
    const std::string text = attr(e, name, required, "");
    std::vector<double> v;
    std::string s = text;
    for (char& c : s)
      if (c == ',') c = ' ';
    std::istringstream in(s);
    std::string tok;
    while (in >> tok) {
      auto x = parseNumber(tok);
      if (!x) fail(e, std::string(e->Name()) + "." + name, "malformed number '" + tok + "'");
      // No field of a machine file holds a value this large in its own unit (um, urad, mm, deg,
      // s, um^2); the lengths and angles are bounded more tightly where they are read.
      if (std::abs(*x) > 1e9)
        fail(e, std::string(e->Name()) + "." + name, "'" + tok + "' is beyond any plausible value");
      v.push_back(*x);
    }
    if (!required && text.empty()) return std::vector<double>(count, 0.0);
    if (count > 0 && v.size() != count)
      fail(e, std::string(e->Name()) + "." + name,
           "expected " + std::to_string(count) + " numbers, found " + std::to_string(v.size()));
    return v;
  }

  double number(const XMLElement* e, const char* name) { return numbers(e, name, 1)[0]; }

  Eigen::Isometry3d frame(const XMLElement* e, double angle_scale) {
    if (!e) return Eigen::Isometry3d::Identity();
    const auto t = numbers(e, "translation", 3, false);
    const auto r = numbers(e, "rotation", 3, false);
    for (int k = 0; k < 3; ++k) {
      if (std::abs(t[k] * length_scale_) > 1e6)
        fail(e, std::string(e->Name()) + ".translation", "beyond 1e6 mm");
      if (std::abs(r[k] * angle_scale) > 1e4 * M_PI / 180.0)
        fail(e, std::string(e->Name()) + ".rotation", "beyond 1e4 deg");
    }
    Vector6d v;
    v << t[0] * length_scale_, t[1] * length_scale_, t[2] * length_scale_, r[0] * angle_scale,
        r[1] * angle_scale, r[2] * angle_scale;
    return linkTransform(v);
  }

  static double angleUnit(const std::string& u, bool* ok) {
    *ok = true;
    if (u == "rad") return 1.0;
    if (u == "deg") return degToRad(1.0);
    if (u == "urad") return 1e-6;
    if (u == "mrad") return uradToRad(1e3);
    if (u == "arcsec") return degToRad(1.0 / 3600.0);
    *ok = false;
    return 0;
  }
  static double lengthUnit(const std::string& u, bool* ok) {
    *ok = true;
    if (u == "mm") return 1.0;
    if (u == "um") return umToMm(1.0);
    if (u == "inch") return 25.4;
    *ok = false;
    return 0;
  }

  int component(const XMLElement* e) {
    const std::string c = attr(e, "component");
    for (int k = 0; k < 6; ++k)
      if (c == kComponentNames[k]) return k;
    fail(e, std::string(e->Name()) + ".component",
         "unknown component '" + c + "' (expected ex, ey, ez, gx, gy or gz)");
  }

  int axisRef(const XMLElement* e, const MachineModel& m) {
    const std::string n = attr(e, "axis");
    const int a = m.axisIndex(n);
    if (a < 0) fail(e, std::string(e->Name()) + ".axis", "no axis named '" + n + "'");
    return a;
  }

  // <effect type=".." axis=".." component=".." [orders="first last"] [varying="true"]
  //         [period_mm=".."] [tau_s=".."] values=".."/>
  // <control name=".." default_units="mm|inch" singular_band_deg="0.0057">
  //   <tcp on="M428" off="M429"/>  <parameter name="_hal[pin]" value="0"/>
  // </control>
  void control(const XMLElement* e, NcControl& c) {
    c.declared = true;
    c.name = attr(e, "name", false, "");
    const std::string u = attr(e, "default_units", false, "mm");
    if (u == "mm")
      c.default_unit_mm = 1.0;
    else if (u == "inch")
      c.default_unit_mm = 25.4;
    else
      fail(e, "control.default_units", "expected mm or inch, found '" + u + "'");
    if (e->Attribute("singular_band_deg")) {
      const double b = number(e, "singular_band_deg");
      if (!(b >= 0 && b <= 5)) fail(e, "control.singular_band_deg", "expected 0 to 5 degrees");
      c.singular_band = degToRad(b);
    }
    c.dialect = attr(e, "dialect", false, "iso");
    if (c.dialect != "iso" && c.dialect != "linuxcnc" && c.dialect != "sinumerik")
      fail(e, "control.dialect", "expected iso, linuxcnc or sinumerik, found '" + c.dialect + "'");
    if (e->Attribute("arc_radius_tolerance_mm")) {
      const double t = number(e, "arc_radius_tolerance_mm");
      if (!(t > 0 && t <= 10)) fail(e, "control.arc_radius_tolerance_mm", "expected 0 to 10 mm");
      c.arc_radius_tolerance_mm = t;
    }
    {
      std::istringstream names(toUpper(attr(e, "swivel_axes", false, "")));
      for (std::string w; names >> w;) c.swivel_axes.push_back(w);
    }
    for (const XMLElement* t = e->FirstChildElement(); t; t = t->NextSiblingElement()) {
      const std::string tag = t->Name();
      if (tag == "tcp") {
        const std::string on = toUpper(attr(t, "on")), off = toUpper(attr(t, "off"));
        if (on.empty() || off.empty() || on == off)
          fail(t, "tcp.on", "expected two different words, e.g. on=\"G43.4\" off=\"G49\"");
        c.tcp_words.emplace_back(on, off);
        std::istringstream ended(toUpper(attr(t, "ended_by", false, "")));
        for (std::string w; ended >> w;) c.tcp_ended_by[on].push_back(w);
      } else if (tag == "parameter") {
        c.parameters[attr(t, "name")] = number(t, "value");
      } else {
        fail(t, "control", "unknown element <" + tag + "> (expected tcp or parameter)");
      }
    }
  }

  EffectSpec effect(const XMLElement* e, const MachineModel& m) {
    const std::string type = attr(e, "type");
    const EffectTraits* t = findEffectType(type);
    if (!t) {
      std::string names;
      for (const EffectTraits& x : effectTypes())
        names += std::string(names.empty() ? "" : ", ") + x.name;
      fail(e, "effect.type", "unknown effect type '" + type + "' (expected " + names + ")");
    }
    EffectSpec spec;
    spec.type = t->type;
    if (spec.type != EffectType::BarLength) {
      spec.axis = axisRef(e, m);
      spec.component = component(e);
    }
    if (spec.type == EffectType::Chebyshev || spec.type == EffectType::Harmonics) {
      const std::vector<double> o = numbers(e, "orders", 2);
      if (o[0] != std::floor(o[0]) || o[1] != std::floor(o[1]) ||
          o[0] < (spec.type == EffectType::Harmonics ? 1 : 0) || o[1] < o[0] || o[1] - o[0] > 7 ||
          o[1] > 30)
        fail(e, "effect.orders", "expected two integers 'first last' with at most eight orders");
      spec.first_order = static_cast<int>(o[0]);
      spec.last_order = static_cast<int>(o[1]);
    }
    if (spec.type == EffectType::Reversal) {
      const std::string v = attr(e, "varying", false, "false");
      if (v != "true" && v != "false") fail(e, "effect.varying", "expected true or false");
      spec.varying = v == "true";
    }
    if (spec.type == EffectType::Periodic) {
      spec.period = number(e, "period_mm");
      if (!(spec.period > 0)) fail(e, "effect.period_mm", "expected a positive period");
    }
    if (spec.type == EffectType::Warmup) {
      spec.tau = number(e, "tau_s");
      if (!(spec.tau > 0)) fail(e, "effect.tau_s", "expected a positive time constant");
    }
    return spec;
  }

  // The machine file, element by element: the root, the axes and their chains, the table and
  // spindle frames, the control, the error model (its units, its elements, the aliases, the
  // values), the identification preferences and uncertainty.
  Machine read(const std::string& xml) {
    tinyxml2::XMLDocument doc;
    if (doc.Parse(xml.data(), xml.size()) != tinyxml2::XML_SUCCESS)
      throw InputError(file_, doc.ErrorLineNum(), 0, "xml", doc.ErrorStr() ? doc.ErrorStr() : "");
    const XMLElement* root = doc.RootElement();
    if (!root || std::string(root->Name()) != "machine")
      fail(root, "machine", "the root element must be <machine>");
    Machine out;
    MachineModel& m = out.model;
    m.name = attr(root, "name");
    bool ok;
    length_scale_ = lengthUnit(attr(root, "length_unit", false, "mm"), &ok);
    if (!ok || length_scale_ == 1e-3) fail(root, "machine.length_unit", "expected mm or inch");
    angle_scale_ = angleUnit(attr(root, "angle_unit", false, "deg"), &ok);
    if (!ok) fail(root, "machine.angle_unit", "expected deg or rad");
    axes(root, m);
    m.last_T_table = frame(root->FirstChildElement("table"), angle_scale_);
    m.last_T_spindle = frame(root->FirstChildElement("spindle"), angle_scale_);
    if (const XMLElement* c = root->FirstChildElement("control")) control(c, m);
    checkPrismaticSpan(root, m);
    const ErrorElements errors = errorElements(root->FirstChildElement("errors"), m);
    m.buildParameterLayout(errors.degrees);
    out.params = Eigen::VectorXd::Zero(m.parameterCount());
    if (const XMLElement* al = root->FirstChildElement("aliases")) aliases(al, m);
    errorValues(errors, out);
    if (const XMLElement* id = root->FirstChildElement("identification")) preferences(id, m);
    namedValues(errors, out);
    if (const XMLElement* u = root->FirstChildElement("identification_uncertainty"))
      identification(u, angle_scale_, out);
    return out;
  }

  // <axis> elements, in file order, and the two chains in their `order`.
  void axes(const XMLElement* root, MachineModel& m) {
    struct Pending {
      Axis axis;
      double order;
      int index;
      bool explicit_order = false;
    };
    std::vector<Pending> pending;
    for (const XMLElement* e = root->FirstChildElement("axis"); e;
         e = e->NextSiblingElement("axis")) {
      Axis ax = axis(e);
      for (const auto& p : pending)
        if (toUpper(p.axis.name) == toUpper(ax.name))
          fail(e, "axis.name", "duplicate axis " + ax.name);
      double order = static_cast<double>(pending.size());
      if (e->Attribute("order")) {
        order = number(e, "order");
        // Two axes at one place in a branch leave the chain's order to chance.
        for (const Pending& p : pending)
          if (p.axis.branch == ax.branch && p.order == order && p.explicit_order)
            fail(e, "axis.order",
                 "order " + formatNumber(order) + " is also axis " + p.axis.name + "'s in the " +
                     (ax.branch == Branch::Workpiece ? "workpiece" : "tool") + " branch");
      }
      pending.push_back(
          {ax, order, static_cast<int>(pending.size()), e->Attribute("order") != nullptr});
      if (pending.size() > static_cast<size_t>(kMaxAxes)) fail(e, "axis", "too many axes");
    }
    if (pending.empty()) fail(root, "axis", "the machine has no axes");
    for (const auto& p : pending) m.axes.push_back(p.axis);
    std::vector<Pending> sorted = pending;
    std::stable_sort(sorted.begin(), sorted.end(),
                     [](const Pending& a, const Pending& b) { return a.order < b.order; });
    for (const auto& p : sorted)
      (p.axis.branch == Branch::Workpiece ? m.workpiece_chain : m.tool_chain).push_back(p.index);
  }

  // One <axis>: name, type, branch, direction, travel, endless, nc_sign, its <link>.
  Axis axis(const XMLElement* e) {
    Axis ax;
    ax.name = attr(e, "name");
    if (ax.name.empty()) fail(e, "axis.name", "empty name");
    const std::string type = attr(e, "type");
    if (type == "prismatic")
      ax.type = JointType::Prismatic;
    else if (type == "rotary")
      ax.type = JointType::Rotary;
    else
      fail(e, "axis.type", "expected prismatic or rotary, found '" + type + "'");
    const std::string branch = attr(e, "branch");
    if (branch == "workpiece")
      ax.branch = Branch::Workpiece;
    else if (branch == "tool")
      ax.branch = Branch::Tool;
    else
      fail(e, "axis.branch", "expected workpiece or tool, found '" + branch + "'");
    const auto d = numbers(e, "direction", 3);
    Eigen::Vector3d dir(d[0], d[1], d[2]);
    if (dir.norm() < 1e-9) fail(e, "axis.direction", "zero vector");
    ax.direction = dir.normalized();
    const double k = ax.isRotary() ? angle_scale_ : length_scale_;
    ax.travel_min = number(e, "min") * k;
    ax.travel_max = number(e, "max") * k;
    // A rotary axis's travel may run many turns (LinuxCNC's XYZAC table: C within 36 000 deg).
    const double bound = ax.isRotary() ? 1e6 * M_PI / 180.0 : 1e6;
    if (std::abs(ax.travel_min) > bound)
      fail(e, "axis.min", ax.isRotary() ? "beyond 1e6 deg" : "beyond 1e6 mm");
    if (std::abs(ax.travel_max) > bound)
      fail(e, "axis.max", ax.isRotary() ? "beyond 1e6 deg" : "beyond 1e6 mm");
    if (!(ax.travel_min < ax.travel_max)) fail(e, "axis.max", "max must exceed min");
    const std::string endless = attr(e, "endless", false, "false");
    if (endless != "true" && endless != "false") fail(e, "axis.endless", "expected true or false");
    ax.endless = endless == "true";
    if (ax.endless && !ax.isRotary()) fail(e, "axis.endless", "only a rotary axis can be endless");
    const std::string sign = attr(e, "nc_sign", false, "1");
    if (sign == "1" || sign == "+1")
      ax.nc_sign = 1;
    else if (sign == "-1")
      ax.nc_sign = -1;
    else
      fail(e, "axis.nc_sign", "expected +1 or -1");
    ax.parent_T_joint = frame(e->FirstChildElement("link"), angle_scale_);
    return ax;
  }

  // <control> and its swivel axes, which must name the machine's two rotary axes.
  void control(const XMLElement* c, MachineModel& m) {
    control(c, m.control);
    for (const std::string& n : m.control.swivel_axes) {
      bool rotary = false;
      for (const Axis& ax : m.axes) rotary = rotary || (ax.isRotary() && toUpper(ax.name) == n);
      if (!rotary || m.control.swivel_axes.size() != 2)
        fail(c, "control.swivel_axes",
             "expected the names of the machine's two rotary axes, found '" + n + "'");
    }
  }

  // The prismatic axes must span their directions: two along one line leave the tool tip
  // unplaceable.
  void checkPrismaticSpan(const XMLElement* root, const MachineModel& m) {
    std::vector<int> prismatic;
    for (size_t a = 0; a < m.axes.size(); ++a)
      if (!m.axes[a].isRotary()) prismatic.push_back(static_cast<int>(a));
    Eigen::MatrixXd D(3, prismatic.size());
    for (size_t k = 0; k < prismatic.size(); ++k)
      D.col(k) = m.axes[prismatic[k]].direction.normalized();
    if (!prismatic.empty() && Eigen::FullPivLU<Eigen::MatrixXd>(D).setThreshold(1e-6).rank() <
                                  static_cast<Eigen::Index>(std::min<size_t>(3, prismatic.size())))
      fail(root->FirstChildElement("axis"), "axis.direction",
           "the prismatic axes' directions are dependent (two along one line?)");
  }

  // What <errors> holds, read before the parameter layout exists (the motion degrees set it).
  struct ErrorValue {
    const XMLElement* e;
    int axis, component;
    std::vector<double> v;
  };
  struct ErrorElements {
    double length = 1.0, angle = 1.0;  // the values' units, in mm and rad
    std::vector<std::array<int, 6>> degrees;
    std::vector<ErrorValue> links, motions, setups;
    std::vector<std::pair<const XMLElement*, double>> named;
    std::vector<const XMLElement*> effects;
    double scale(int component) const { return isAngularComponent(component) ? angle : length; }
  };

  // <errors>: its source, units and default degree, then its elements.
  ErrorElements errorElements(const XMLElement* errs, MachineModel& m) {
    ErrorElements out;
    int default_degree = 3;
    if (errs) {
      bool ok;
      const std::string source = attr(errs, "source", false, "");
      static const char* sources[] = {"", "none", "measured", "identified", "simulated"};
      if (std::find_if(std::begin(sources), std::end(sources),
                       [&](const char* x) { return source == x; }) == std::end(sources))
        fail(errs, "errors.source", "expected none, measured, identified or simulated");
      m.errors_source = source;
      out.length = lengthUnit(attr(errs, "length_unit", false, "mm"), &ok);
      if (!ok) fail(errs, "errors.length_unit", "expected mm, um or inch");
      out.angle = angleUnit(attr(errs, "angle_unit", false, "rad"), &ok);
      if (!ok) fail(errs, "errors.angle_unit", "expected rad, urad, mrad, deg or arcsec");
      if (errs->Attribute("default_degree"))
        default_degree = degree(errs, "errors.default_degree", "default_degree");
    }
    out.degrees.resize(m.axes.size());
    for (auto& d : out.degrees) d.fill(default_degree);
    for (const XMLElement* e = errs ? errs->FirstChildElement() : nullptr; e;
         e = e->NextSiblingElement()) {
      const std::string tag = e->Name();
      if (tag == "link") {
        out.links.push_back({e, axisRef(e, m), component(e), {number(e, "value")}});
      } else if (tag == "motion") {
        ErrorValue v{e, axisRef(e, m), component(e), numbers(e, "coefficients", 0)};
        int deg = std::max<int>(default_degree, static_cast<int>(v.v.size()) - 1);
        if (e->Attribute("degree")) {
          deg = degree(e, "motion.degree", "degree");
          if (static_cast<int>(v.v.size()) > deg + 1)
            fail(e, "motion.coefficients", "more coefficients than degree + 1");
        }
        out.degrees[v.axis][v.component] = deg;
        out.motions.push_back(v);
      } else if (tag == "setup") {
        const std::string f = attr(e, "frame");
        if (f != "workpiece" && f != "tool")
          fail(e, "setup.frame", "expected workpiece or tool, found '" + f + "'");
        out.setups.push_back({e, f == "workpiece" ? 0 : 1, component(e), {number(e, "value")}});
      } else if (tag == "param") {
        out.named.emplace_back(e, number(e, "value"));
      } else if (tag == "effect") {
        out.effects.push_back(e);
      } else {
        fail(e, "errors", "unknown element <" + tag + ">");
      }
    }
    return out;
  }

  // A Chebyshev degree attribute: an integer from 0 to 20.
  int degree(const XMLElement* e, const char* field, const char* name) {
    const double d = number(e, name);
    if (d < 0 || d > 20 || d != std::floor(d)) fail(e, field, "expected an integer from 0 to 20");
    return static_cast<int>(d);
  }

  // <aliases>: other names for parameters.
  void aliases(const XMLElement* al, MachineModel& m) {
    for (const XMLElement* e = al->FirstChildElement("alias"); e;
         e = e->NextSiblingElement("alias")) {
      const std::string name = attr(e, "name"), target = attr(e, "parameter");
      const int p = m.findParameter(target);
      if (p < 0) fail(e, "alias.parameter", "no parameter named '" + target + "'");
      if (m.findParameter(name) >= 0) fail(e, "alias.name", "'" + name + "' is already a name");
      m.aliases.push_back({name, p, attr(e, "description", false, "")});
    }
  }

  // The effects (appended to the layout), the link and the motion errors' values.
  void errorValues(const ErrorElements& errors, Machine& out) {
    MachineModel& m = out.model;
    for (const XMLElement* e : errors.effects) {
      const int first = m.parameterCount();
      const EffectSpec spec = effect(e, m);
      m.addEffect(spec);
      const int size = m.parameterCount() - first;
      const std::vector<double> v = numbers(e, "values", 0);
      if (static_cast<int>(v.size()) != size)
        fail(e, "effect.values",
             "expected " + std::to_string(size) + " values, found " + std::to_string(v.size()));
      out.params.conservativeResize(m.parameterCount());
      for (int k = 0; k < size; ++k)
        out.params[first + k] =
            v[k] * (spec.axis < 0 ? errors.length : errors.scale(spec.component));
    }
    for (const ErrorValue& v : errors.links) {
      const int b = std::find_if(m.blocks.begin(), m.blocks.end(),
                                 [&](const ParameterBlock& x) {
                                   return x.kind == BlockKind::LinkError && x.axis == v.axis;
                                 }) -
                    m.blocks.begin();
      out.params[m.blocks[b].offset + v.component] = v.v[0] * errors.scale(v.component);
    }
    for (const ErrorValue& v : errors.motions) {
      const ParameterBlock& b = m.blocks[m.motionBlock(v.axis, v.component)];
      for (size_t k = 0; k < v.v.size(); ++k)
        out.params[b.offset + k] = v.v[k] * errors.scale(v.component);
    }
  }

  // <identification><prefer model= parameters=/>: the parameters a minimal set keeps first.
  void preferences(const XMLElement* id, MachineModel& m) {
    for (const XMLElement* e = id->FirstChildElement("prefer"); e;
         e = e->NextSiblingElement("prefer")) {
      const std::string model = attr(e, "model");
      if (model != "link" && model != "motion")
        fail(e, "prefer.model", "expected link or motion, found '" + model + "'");
      std::istringstream in(attr(e, "parameters"));
      std::string name;
      while (in >> name) {
        const int p = m.findParameter(name);
        if (p < 0) fail(e, "prefer.parameters", "no parameter named '" + name + "'");
        m.preferred[model].push_back(p);
      }
    }
  }

  // <param name=> values (after the aliases exist) and the set-up errors.
  void namedValues(const ErrorElements& errors, Machine& out) {
    const MachineModel& m = out.model;
    for (const auto& [e, value] : errors.named) {
      const std::string name = attr(e, "name");
      const int p = m.findParameter(name);
      if (p < 0) fail(e, "param.name", "no parameter named '" + name + "'");
      out.params[p] = value * (m.parameters[p].angular ? errors.angle : errors.length);
    }
    for (const ErrorValue& v : errors.setups) {
      const BlockKind kind = v.axis == 0 ? BlockKind::WorkpieceSetup : BlockKind::ToolSetup;
      for (const ParameterBlock& b : m.blocks)
        if (b.kind == kind) out.params[b.offset + v.component] = v.v[0] * errors.scale(v.component);
    }
  }

  // <identification_uncertainty readings="n"> with <covered axis= min= max=/> (machine units)
  // and <covariance parameters="codes"><row>..</row></covariance> (um and urad).
  void identification(const XMLElement* u, double angle, Machine& out) {
    const MachineModel& m = out.model;
    IdentificationUncertainty& id = out.identification;
    id.readings = 0;
    if (u->Attribute("readings")) {
      const double n = number(u, "readings");
      if (!(n >= 0 && n <= 1e9) || n != std::floor(n))
        fail(u, "identification_uncertainty.readings", "expected a whole number from 0 to 1e9");
      id.readings = static_cast<int>(n);
    }
    if (u->Attribute("lack_of_fit_um")) {
      const double v = number(u, "lack_of_fit_um");
      if (!(v >= 0 && v <= 1e4))
        fail(u, "identification_uncertainty.lack_of_fit_um", "expected 0 to 10000 um");
      id.lack_of_fit_mm = umToMm(v);
    }
    if (u->Attribute("spindle_tilt_urad")) {
      const double v = number(u, "spindle_tilt_urad");
      if (const std::string problem = outOfRange(Quantity::SpindleTilt, v); !problem.empty())
        fail(u, "identification_uncertainty.spindle_tilt_urad", problem);
      id.spindle_tilt_rad = v * 1e-6;
    }
    for (const XMLElement* c = u->FirstChildElement("covered"); c;
         c = c->NextSiblingElement("covered")) {
      const int a = m.axisIndex(attr(c, "axis"));
      if (a < 0) fail(c, "covered.axis", "no axis named '" + attr(c, "axis") + "'");
      if (id.covered_min.empty()) {
        id.covered_min.assign(m.axes.size(), -std::numeric_limits<double>::infinity());
        id.covered_max.assign(m.axes.size(), std::numeric_limits<double>::infinity());
      }
      const double k = m.axes[a].isRotary() ? angle : length_scale_;
      id.covered_min[a] = number(c, "min") * k;
      id.covered_max[a] = number(c, "max") * k;
      if (!(id.covered_min[a] <= id.covered_max[a])) fail(c, "covered.min", "min above max");
    }
    const XMLElement* cov = u->FirstChildElement("covariance");
    if (!cov) return;
    std::istringstream names(attr(cov, "parameters"));
    std::vector<double> unit;
    for (std::string name; names >> name;) {
      const int p = m.findParameter(name);
      if (p < 0)
        fail(cov, "covariance.parameters", "no parameter named '" + name.substr(0, 60) + "'");
      id.parameters.push_back(p);
      unit.push_back(m.parameters[p].angular ? uradToRad(1.0) : umToMm(1.0));
    }
    const size_t n = id.parameters.size();
    id.covariance.resize(n, n);
    size_t r = 0;
    for (const XMLElement* row = cov->FirstChildElement("row"); row;
         row = row->NextSiblingElement("row"), ++r) {
      if (r >= n) fail(row, "covariance.row", "more rows than parameters");
      std::istringstream in(row->GetText() ? row->GetText() : "");
      size_t c = 0;
      for (std::string tok; in >> tok; ++c) {
        const auto x = parseNumber(tok);
        if (!x || c >= n)
          fail(row, "covariance.row", x ? "more values than parameters" : "malformed number");
        id.covariance(r, c) = *x * unit[r] * unit[c];
      }
      if (c != n) fail(row, "covariance.row", "expected " + std::to_string(n) + " values");
    }
    if (r != n) fail(cov, "covariance", "expected " + std::to_string(n) + " rows");
    for (size_t i = 0; i < n; ++i) {
      if (!(id.covariance(i, i) >= 0)) fail(cov, "covariance", "a negative variance");
      for (size_t j = 0; j < i; ++j)
        if (std::abs(id.covariance(i, j) - id.covariance(j, i)) >
            1e-9 * std::sqrt(id.covariance(i, i) * id.covariance(j, j)) + 1e-300)
          fail(cov, "covariance", "not symmetric");
    }
  }

 private:
  std::string file_;
  double length_scale_ = 1.0;
  double angle_scale_ = 1.0;  // of the machine's own angles (deg or rad), in rad
};

}  // namespace

namespace {

// The machine file written with tinyxml2's printer (it escapes every attribute and text).
class MachineXmlWriter {
 public:
  explicit MachineXmlWriter(const Machine& machine) : machine_(machine), m_(machine.model) {}

  std::string write(const std::string& comment) {
    p_.PushDeclaration("xml version=\"1.0\" encoding=\"UTF-8\"");
    if (!comment.empty()) {
      std::string text = comment;  // XML forbids "--" inside a comment
      for (size_t k = text.find("--"); k != std::string::npos; k = text.find("--", k))
        text.replace(k, 2, "- -");
      p_.PushComment((" " + text + " ").c_str());
    }
    p_.OpenElement("machine");
    attr("name", m_.name);
    attr("length_unit", "mm");
    attr("angle_unit", "deg");
    for (size_t a = 0; a < m_.axes.size(); ++a) axis(static_cast<int>(a));
    frame("table", m_.last_T_table);
    frame("spindle", m_.last_T_spindle);
    if (m_.control.declared) control();
    errors();
    aliases();
    identificationUncertainty();
    preferred();
    p_.CloseElement();
    return p_.CStr();
  }

 private:
  void attr(const char* name, const std::string& value) { p_.PushAttribute(name, value.c_str()); }
  void attr(const char* name, double value) { attr(name, formatNumber(value)); }
  static std::string joined(const std::vector<std::string>& words) {
    std::string out;
    for (const std::string& w : words) out += (out.empty() ? "" : " ") + w;
    return out;
  }
  // A frame: translation (mm) and rotation x, y, z (deg; R = Rz Ry Rx).
  void frameAttributes(const Eigen::Isometry3d& T) {
    const Eigen::Matrix3d& R = T.linear();
    const double ry = std::asin(std::clamp(-R(2, 0), -1.0, 1.0));
    const double rx = std::atan2(R(2, 1), R(2, 2)), rz = std::atan2(R(1, 0), R(0, 0));
    const Eigen::Vector3d t = T.translation();
    attr("translation", joined({formatNumber(t.x()), formatNumber(t.y()), formatNumber(t.z())}));
    attr("rotation", joined({formatNumber(radToDeg(rx)), formatNumber(radToDeg(ry)),
                             formatNumber(radToDeg(rz))}));
  }
  void frame(const char* element, const Eigen::Isometry3d& T) {
    p_.OpenElement(element);
    frameAttributes(T);
    p_.CloseElement();
  }
  void axis(int a) {
    const Axis& ax = m_.axes[a];
    const auto& chain = ax.branch == Branch::Workpiece ? m_.workpiece_chain : m_.tool_chain;
    const int order =
        static_cast<int>(std::find(chain.begin(), chain.end(), a) - chain.begin()) + 1;
    const double k = ax.isRotary() ? radToDeg(1.0) : 1.0;
    p_.OpenElement("axis");
    attr("name", ax.name);
    attr("type", ax.isRotary() ? "rotary" : "prismatic");
    attr("branch", ax.branch == Branch::Workpiece ? "workpiece" : "tool");
    attr("order", std::to_string(order));
    attr("direction", joined({formatNumber(ax.direction.x()), formatNumber(ax.direction.y()),
                              formatNumber(ax.direction.z())}));
    attr("min", ax.travel_min * k);
    attr("max", ax.travel_max * k);
    attr("nc_sign", std::to_string(ax.nc_sign));
    if (ax.endless) attr("endless", "true");
    frame("link", ax.parent_T_joint);
    p_.CloseElement();
  }
  void control() {
    const NcControl& c = m_.control;
    p_.OpenElement("control");
    attr("name", c.name);
    attr("default_units", c.default_unit_mm == 25.4 ? "inch" : "mm");
    attr("singular_band_deg", radToDeg(c.singular_band));
    if (c.dialect != "iso") attr("dialect", c.dialect);
    if (c.arc_radius_tolerance_mm > 0) attr("arc_radius_tolerance_mm", c.arc_radius_tolerance_mm);
    if (!c.swivel_axes.empty()) {
      std::string names;
      for (const std::string& n : c.swivel_axes) names += (names.empty() ? "" : " ") + n;
      attr("swivel_axes", names);
    }
    for (const auto& [on, off] : c.tcp_words) {
      p_.OpenElement("tcp");
      attr("on", on);
      attr("off", off);
      if (auto it = c.tcp_ended_by.find(on); it != c.tcp_ended_by.end()) {
        std::string words;
        for (const std::string& w : it->second) words += (words.empty() ? "" : " ") + w;
        attr("ended_by", words);
      }
      p_.CloseElement();
    }
    for (const auto& [name, value] : c.parameters) {
      p_.OpenElement("parameter");
      attr("name", name);
      attr("value", value);
      p_.CloseElement();
    }
    p_.CloseElement();
  }
  // A value in the file's error units: um, urad.
  std::string value(int p) const {
    return formatNumber(m_.parameters[p].angular ? radToUrad(machine_.params[p])
                                                 : mmToUm(machine_.params[p]));
  }
  std::string values(int offset, int count) const {
    std::vector<std::string> v;
    for (int k = 0; k < count; ++k) v.push_back(value(offset + k));
    return joined(v);
  }
  void component(const char* element, const char* key, const std::string& key_value, int c, int p) {
    p_.OpenElement(element);
    attr(key, key_value);
    attr("component", kComponentNames[c]);
    attr("value", value(p));
    p_.CloseElement();
  }
  void effect(const ParameterBlock& b) {
    const EffectSpec& e = m_.effects[b.effect];
    p_.OpenElement("effect");
    attr("type", traitsOf(e.type).name);
    if (e.axis >= 0) {
      attr("axis", m_.axes[e.axis].name);
      attr("component", b.component >= 0 ? kComponentNames[b.component] : "");
    }
    if (e.type == EffectType::Chebyshev || e.type == EffectType::Harmonics)
      attr("orders", std::to_string(e.first_order) + " " + std::to_string(e.last_order));
    if (e.type == EffectType::Reversal && e.varying) attr("varying", "true");
    if (e.type == EffectType::Periodic) attr("period_mm", e.period);
    if (e.type == EffectType::Warmup) attr("tau_s", e.tau);
    attr("values", values(b.offset, b.size));
    p_.CloseElement();
  }
  // Errors in um and urad; the most common motion degree is the default.
  void errors() {
    std::map<int, int> degree_count;
    for (const ParameterBlock& b : m_.blocks)
      if (b.kind == BlockKind::MotionError) ++degree_count[b.degree];
    int def = 3, best = -1;
    for (const auto& [d, c] : degree_count)
      if (c > best) {
        best = c;
        def = d;
      }
    p_.OpenElement("errors");
    if (!m_.errors_source.empty()) attr("source", m_.errors_source);
    attr("length_unit", "um");
    attr("angle_unit", "urad");
    attr("default_degree", std::to_string(def));
    const Eigen::VectorXd& q = machine_.params;
    for (const ParameterBlock& b : m_.blocks) {
      switch (b.kind) {
        case BlockKind::LinkError:
          for (int c = 0; c < 6; ++c)
            if (q[b.offset + c] != 0.0)
              component("link", "axis", m_.axes[b.axis].name, c, b.offset + c);
          break;
        case BlockKind::MotionError: {
          bool any = b.degree != def;
          for (int k = 0; k <= b.degree; ++k) any |= q[b.offset + k] != 0.0;
          if (!any) break;
          p_.OpenElement("motion");
          attr("axis", m_.axes[b.axis].name);
          attr("component", kComponentNames[b.component]);
          attr("degree", std::to_string(b.degree));
          attr("coefficients", values(b.offset, b.degree + 1));
          p_.CloseElement();
          break;
        }
        case BlockKind::WorkpieceSetup:
        case BlockKind::ToolSetup:
          for (int c = 0; c < 6; ++c)
            if (q[b.offset + c] != 0.0)
              component("setup", "frame",
                        b.kind == BlockKind::WorkpieceSetup ? "workpiece" : "tool", c,
                        b.offset + c);
          break;
        case BlockKind::Effect:
          effect(b);
          break;
      }
    }
    p_.CloseElement();
  }
  void aliases() {
    if (m_.aliases.empty()) return;
    p_.OpenElement("aliases");
    for (const ParameterAlias& a : m_.aliases) {
      p_.OpenElement("alias");
      attr("name", a.name);
      attr("parameter", m_.parameters[a.parameter].iso_code);
      attr("description", a.description);
      p_.CloseElement();
    }
    p_.CloseElement();
  }
  void identificationUncertainty() {
    const IdentificationUncertainty& id = machine_.identification;
    if (id.empty() && id.covered_min.empty()) return;
    p_.OpenElement("identification_uncertainty");
    attr("readings", std::to_string(id.readings));
    if (id.lack_of_fit_mm > 0) attr("lack_of_fit_um", mmToUm(id.lack_of_fit_mm));
    if (id.spindle_tilt_rad > 0) attr("spindle_tilt_urad", id.spindle_tilt_rad * 1e6);
    p_.PushComment(
        " the joint ranges the readings covered (mm, deg), and the covariance of the identified "
        "values (um and urad) ");
    for (size_t a = 0; a < id.covered_min.size() && a < m_.axes.size(); ++a) {
      const double k = m_.axes[a].isRotary() ? radToDeg(1.0) : 1.0;
      p_.OpenElement("covered");
      attr("axis", m_.axes[a].name);
      attr("min", id.covered_min[a] * k);
      attr("max", id.covered_max[a] * k);
      p_.CloseElement();
    }
    if (!id.empty()) {
      std::vector<std::string> names;
      std::vector<double> unit;
      for (int p : id.parameters) {
        names.push_back(m_.parameters[p].iso_code);
        unit.push_back(m_.parameters[p].angular ? radToUrad(1.0) : mmToUm(1.0));
      }
      p_.OpenElement("covariance");
      attr("parameters", joined(names));
      for (Eigen::Index i = 0; i < id.covariance.rows(); ++i) {
        std::vector<std::string> row;
        for (Eigen::Index j = 0; j < id.covariance.cols(); ++j)
          row.push_back(formatNumber(id.covariance(i, j) * unit[i] * unit[j]));
        p_.OpenElement("row");
        p_.PushText(joined(row).c_str());
        p_.CloseElement();
      }
      p_.CloseElement();
    }
    p_.CloseElement();
  }
  void preferred() {
    if (m_.preferred.empty()) return;
    p_.OpenElement("identification");
    for (const auto& [model, list] : m_.preferred) {
      std::vector<std::string> names;
      for (int p : list) names.push_back(m_.parameters[p].iso_code);
      p_.OpenElement("prefer");
      attr("model", model);
      attr("parameters", joined(names));
      p_.CloseElement();
    }
    p_.CloseElement();
  }

  const Machine& machine_;
  const MachineModel& m_;
  tinyxml2::XMLPrinter p_;
};

}  // namespace

std::string formatMachineXml(const Machine& machine, const std::string& comment) {
  return MachineXmlWriter(machine).write(comment);
}

Machine parseMachineXml(const std::string& xml, const std::string& file_name) {
  return Reader(file_name).read(xml);
}

Machine readMachineFile(const std::string& path) { return parseMachineXml(readFile(path), path); }

}  // namespace tolver
