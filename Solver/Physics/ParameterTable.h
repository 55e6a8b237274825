// The user-facing parameters of the physics, each declared once: its Parameters field, the name
// ParaView and the field data use, the tools' option, label, group, unit, default, valid range,
// the GUI's slider range and one line of help. Everything that lists parameters reads this table:
// the range checks and their messages (Parameters::validate), the run's identity
// (sameParameters), the tools' options (ToolOptions), the proxy XML (generated at build time by
// Plugin/ProxyXml.cpp), the filter's setters and cache key, the field-data record and the
// messages in the GUI's terms (Filters/). Adding a parameter is a row here plus the physics that
// reads it. Every row is part of a run's identity: changing one restarts the run from its start
// (the state after step k depends on all of them); what may change mid-run without a restart
// (the frames, checkpoints, the surface's settings) is the filter's, not a row here.
#pragma once

#include "Parameters.h"

#include <string>
#include <vector>

namespace pbf
{

enum class ParameterType
{
  Real,    // a double
  Integer, // an int
  Boolean, // 0 or 1
  Vector,  // three doubles
};

// Where a value may lie: [min, max], either end open, either end unbounded (infinity).
struct ValidRange
{
  double min;
  double max;
  bool minOpen;
  bool maxOpen;
  // "must be > 0", "must lie in (1, 4]", ... as Parameters::validate says it.
  std::string rule() const;
  bool contains(double value) const;
};

struct ParameterSpec
{
  const char* field;    // the Parameters member, as solver messages name it: "restDensity"
  const char* property; // ParaView's property, the field data array: "RestDensity"
  const char* option;   // the tools' --option: "rest-density"
  const char* label;    // the GUI's label: "Rest Density"
  const char* group;    // the GUI's property group: "Solver"
  const char* unit;     // SI unit, "" when dimensionless
  ParameterType type;
  ValidRange valid;     // what the solver accepts (the error names the field and the value)
  double sliderMin;     // the GUI's range domain (a slider's ends, not a limit)
  double sliderMax;
  bool advanced;        // shown with the panel's advanced toggle only
  // The GUI shows or enables it only while another property has a value, as
  // "mode property value" ("enabled_state AdaptiveIterations 1"); null: always.
  const char* decorator;
  const char* why;      // appended to a range error: what the range means ("" when plain)
  const char* help;     // the property's documentation
  double (*get)(const Parameters&, int component);
  void (*set)(Parameters&, int component, double value);

  int components() const { return type == ParameterType::Vector ? 3 : 1; }
  // The default, component by component, from Parameters' own initialisers.
  double defaultValue(int component = 0) const { return get(Parameters(), component); }
};

// Every row, in the GUI's order within each group.
const std::vector<ParameterSpec>& parameterTable();

// The row whose field or property is `name`; null when there is none.
const ParameterSpec* findParameter(const std::string& name);

// Throws InvalidInput "field = value: rule" for the first value outside its valid range.
void validateTableParameters(const Parameters& p);

// Whether every row's value is the same in a and b (bit for bit).
bool sameTableParameters(const Parameters& a, const Parameters& b);

} // namespace pbf
