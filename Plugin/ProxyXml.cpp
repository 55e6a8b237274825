// The build's generator of the plugin's proxy XML:  pbf_proxy_xml TEMPLATE OUTPUT
// Copies TEMPLATE (Plugin/PositionBasedFluids.xml.in) to OUTPUT, writing at each
// "<!-- @PBF_PROPERTIES group@ -->" the properties of the parameter table's rows of that group,
// and at each "<!-- @PBF_GROUP group@ -->" their names for the panel's property group. A row
// whose group has no marker is an error: every parameter must reach the GUI.
#include "ParameterTable.h"

#include <charconv>
#include <fstream>
#include <iostream>
#include <set>
#include <sstream>
#include <string>

namespace
{

// The shortest text that reads back as the same double, so the proxy's defaults are the
// solver's to the bit.
std::string shortest(double value)
{
  char text[64];
  const auto result = std::to_chars(text, text + sizeof(text), value);
  return std::string(text, result.ptr);
}

std::string repeated(const pbf::ParameterSpec& spec, double value)
{
  std::string out;
  for (int c = 0; c < spec.components(); ++c)
  {
    out += (c ? " " : "") + shortest(value);
  }
  return out;
}

std::string escaped(const std::string& text)
{
  std::string out;
  for (char c : text)
  {
    out += c == '&' ? std::string("&amp;") : c == '<' ? std::string("&lt;")
      : c == '>' ? std::string("&gt;") : std::string(1, c);
  }
  return out;
}

// The documentation wrapped at 90 columns, indented for its place in the file.
std::string wrapped(const std::string& text, const std::string& indent)
{
  std::istringstream words(escaped(text));
  std::string out, line, word;
  while (words >> word)
  {
    if (!line.empty() && indent.size() + line.size() + 1 + word.size() > 98)
    {
      out += indent + line + "\n";
      line.clear();
    }
    line += (line.empty() ? "" : " ") + word;
  }
  return out + (line.empty() ? "" : indent + line + "\n");
}

std::string property(const pbf::ParameterSpec& spec)
{
  using T = pbf::ParameterType;
  const bool real = spec.type == T::Real || spec.type == T::Vector;
  const std::string element = real ? "DoubleVectorProperty" : "IntVectorProperty";
  std::ostringstream out;
  out << "      <" << element << " name=\"" << spec.property << "\"\n"
      << "          label=\"" << spec.label << "\"\n"
      << "          command=\"SetParameter\"\n"
      << "          initial_string=\"" << spec.property << "\"\n"
      << "          number_of_elements=\"" << spec.components() << "\"\n"
      << "          default_values=\"";
  for (int c = 0; c < spec.components(); ++c)
  {
    out << (c ? " " : "") << shortest(spec.defaultValue(c));
  }
  out << "\"" << (spec.advanced ? "\n          panel_visibility=\"advanced\"" : "") << ">\n";
  if (spec.type == T::Boolean)
  {
    out << "        <BooleanDomain name=\"bool\" />\n";
  }
  else
  {
    out << "        <" << (real ? "DoubleRangeDomain" : "IntRangeDomain") << " name=\"range\" min=\""
        << repeated(spec, spec.sliderMin) << "\" max=\"" << repeated(spec, spec.sliderMax)
        << "\" />\n";
  }
  if (spec.decorator)
  {
    std::istringstream words(spec.decorator);
    std::string mode, on, value;
    words >> mode >> on >> value;
    out << "        <Hints>\n"
        << "          <PropertyWidgetDecorator type=\"GenericDecorator\" mode=\"" << mode
        << "\" property=\"" << on << "\" value=\"" << value << "\" />\n"
        << "        </Hints>\n";
  }
  out << "        <Documentation>\n" << wrapped(spec.help, "          ")
      << "        </Documentation>\n"
      << "      </" << element << ">\n\n";
  return out.str();
}

// The group named by a marker line such as "<!-- @PBF_PROPERTIES Fluid@ -->", or "".
std::string markerGroup(const std::string& line, const std::string& marker)
{
  const std::size_t at = line.find("@" + marker + " ");
  if (at == std::string::npos)
  {
    return "";
  }
  const std::size_t begin = at + marker.size() + 2;
  const std::size_t end = line.find('@', begin);
  return end == std::string::npos ? "" : line.substr(begin, end - begin);
}

} // namespace

int main(int argc, char** argv)
{
  if (argc != 3)
  {
    std::cerr << "usage: pbf_proxy_xml TEMPLATE OUTPUT\n";
    return 2;
  }
  std::ifstream in(argv[1]);
  if (!in)
  {
    std::cerr << "pbf_proxy_xml: cannot read " << argv[1] << "\n";
    return 1;
  }
  std::ostringstream out;
  std::set<std::string> written, grouped;
  for (std::string line; std::getline(in, line);)
  {
    const std::string properties = markerGroup(line, "PBF_PROPERTIES");
    const std::string group = markerGroup(line, "PBF_GROUP");
    if (!properties.empty())
    {
      for (const pbf::ParameterSpec& spec : pbf::parameterTable())
      {
        if (properties == spec.group)
        {
          out << property(spec);
          written.insert(spec.property);
        }
      }
    }
    else if (!group.empty())
    {
      const std::string indent = line.substr(0, line.find('<'));
      for (const pbf::ParameterSpec& spec : pbf::parameterTable())
      {
        if (group == spec.group)
        {
          out << indent << "<Property name=\"" << spec.property << "\" />\n";
          grouped.insert(spec.property);
        }
      }
    }
    else
    {
      out << line << "\n";
    }
  }
  for (const pbf::ParameterSpec& spec : pbf::parameterTable())
  {
    if (!written.count(spec.property) || !grouped.count(spec.property))
    {
      std::cerr << "pbf_proxy_xml: " << argv[1] << " has no @PBF_PROPERTIES " << spec.group
                << "@ and @PBF_GROUP " << spec.group << "@ markers for " << spec.property << "\n";
      return 1;
    }
  }
  std::ofstream(argv[2]) << out.str();
  return 0;
}
