// How Simulation's messages write numbers, shared by the files that make Simulation. Private to
// Solver/Run/.
#pragma once

#include <sstream>
#include <string>

namespace pbf::simulationtext
{

// Three significant digits: enough to name the value a message is about.
inline std::string number(double value)
{
  std::ostringstream out;
  out.precision(3);
  out << value;
  return out.str();
}

} // namespace pbf::simulationtext
