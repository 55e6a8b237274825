#include "vtkPBFTranslate.h"

#include "vtkDataArray.h"
#include "vtkPointData.h"
#include "vtkPointSet.h"

#include "ParameterTable.h"
#include "Parameters.h"

#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <strings.h>
#include <sstream>
#include <utility>
#include <vector>

namespace
{

std::string FormatPoint(const double x[3])
{
  std::ostringstream text;
  text << "(" << x[0] << ", " << x[1] << ", " << x[2] << ")";
  return text.str();
}

} // namespace

//------------------------------------------------------------------------------
pbf::ParticleBatch vtkPBFBatchFromInput(vtkPointSet* input, vtkIdType first, vtkIdType total)
{
  const vtkIdType n = input->GetNumberOfPoints();
  const vtkIdType all = total < 0 ? n : total;
  if (all < 2)
  {
    // One particle has no neighbour: no density to constrain, nothing that behaves as a fluid.
    throw pbf::InvalidInput("input number of points = " + std::to_string(all) +
      ": the filter needs at least 2 points to become the fluid (a particle alone has no "
      "neighbour within the smoothing length, so it only falls)");
  }
  vtkDataArray* velocity = input->GetPointData()->GetArray("velocity");
  if (velocity && velocity->GetNumberOfComponents() != 3)
  {
    throw pbf::InvalidInput("input point array \"velocity\" has " +
      std::to_string(velocity->GetNumberOfComponents()) +
      " components: an initial velocity needs 3 (rename the array to ignore it)");
  }
  // Each point's liquid, its index in the scene's "liquids" (whose count the stepper checks).
  vtkDataArray* liquid = input->GetPointData()->GetArray("liquid");
  if (liquid && liquid->GetNumberOfComponents() != 1)
  {
    throw pbf::InvalidInput("input point array \"liquid\" has " +
      std::to_string(liquid->GetNumberOfComponents()) +
      " components: a point's liquid is one index into the scene's \"liquids\"");
  }
  pbf::ParticleBatch batch;
  if (liquid)
  {
    batch.liquid.resize(static_cast<std::size_t>(n));
  }
  batch.position.resize(static_cast<std::size_t>(n));
  batch.velocity.resize(static_cast<std::size_t>(n), pbf::Vec3d{ 0, 0, 0 });
  batch.id.resize(static_cast<std::size_t>(n));
  for (vtkIdType i = 0; i < n; ++i)
  {
    double x[3];
    input->GetPoint(i, x);
    if (!std::isfinite(x[0]) || !std::isfinite(x[1]) || !std::isfinite(x[2]))
    {
      throw pbf::InvalidInput("input point " + std::to_string(first + i) + " = " + FormatPoint(x) +
        ": coordinates must be finite");
    }
    const auto k = static_cast<std::size_t>(i);
    batch.position[k] = pbf::Vec3d{ x[0], x[1], x[2] };
    if (velocity)
    {
      double v[3];
      velocity->GetTuple(i, v);
      if (!std::isfinite(v[0]) || !std::isfinite(v[1]) || !std::isfinite(v[2]))
      {
        throw pbf::InvalidInput("input velocity of point " + std::to_string(first + i) + " = " +
          FormatPoint(v) + ": must be finite");
      }
      batch.velocity[k] = pbf::Vec3d{ v[0], v[1], v[2] };
    }
    batch.id[k] = static_cast<std::int64_t>(first + i);
    if (liquid)
    {
      const double l = liquid->GetTuple1(i);
      if (!(l >= 0 && l < pbf::kMaxLiquids && l == std::floor(l)))
      {
        throw pbf::InvalidInput("input liquid of point " + std::to_string(first + i) + " = " +
          std::to_string(l) + ": must be an index into the scene's \"liquids\" (0 to " +
          std::to_string(pbf::kMaxLiquids - 1) + ")");
      }
      batch.liquid[k] = static_cast<std::uint8_t>(l);
    }
  }
  return batch;
}


//------------------------------------------------------------------------------
std::string vtkPBFInUserTerms(std::string text)
{
  const std::pair<const char*, const char*> phrases[] = {
    { "lower timeStep (more substeps per frame) or use automatic time stepping",
      "raise Substeps Per Frame (or lower Frame Interval), or set Time Stepping to Automatic" },
    { "lower cflNumber or the largest time step", "lower CFL Number or Max Time Step" },
    { "lower timeStep first",
      "lower the time step first (Time Stepping Automatic, a smaller CFL Number or Max Time Step; "
      "with Fixed steps more Substeps Per Frame)" },
    { "raise relaxation", "raise Relaxation Epsilon" },
  };
  for (const auto& phrase : phrases)
  {
    for (std::size_t at = text.find(phrase.first); at != std::string::npos;
         at = text.find(phrase.first, at + std::strlen(phrase.second)))
    {
      text.replace(at, std::strlen(phrase.first), phrase.second);
    }
  }
  // The solver's field names, as the GUI labels them (the parameter table's rows); the time
  // step of a message is the one the run used, MaxTimeStep only when automatic.
  std::vector<std::pair<const char*, const char*>> fields = { { "timeStep", "the time step" } };
  for (const pbf::ParameterSpec& spec : pbf::parameterTable())
  {
    // A label that is the field's own word capitalised (gravity, unilateral) says nothing more.
    if (std::strcmp(spec.field, "timeStep") != 0 && strcasecmp(spec.field, spec.label) != 0)
    {
      fields.emplace_back(spec.field, spec.label);
    }
  }
  auto isWordCharacter = [](char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_'; };
  for (const auto& field : fields)
  {
    const std::size_t length = std::strlen(field.first);
    for (std::size_t at = text.find(field.first); at != std::string::npos;
         at = text.find(field.first, at + 1))
    {
      // After a '.' it is a key of a scene file (".liquids[1].restDensity"), not a property.
      const bool whole = (at == 0 || (!isWordCharacter(text[at - 1]) && text[at - 1] != '.')) &&
        (at + length == text.size() || !isWordCharacter(text[at + length]));
      if (whole)
      {
        text.replace(at, length, field.second);
      }
    }
  }
  return text;
}

//------------------------------------------------------------------------------
std::string vtkPBFInvalidTimeProperty(double frameInterval, int numberOfFrames, bool automatic,
  int substepsPerFrame, double maxTimeStep)
{
  std::ostringstream text;
  if (!std::isfinite(frameInterval) || frameInterval <= 0.0)
  {
    text << "Frame Interval = " << frameInterval << ": must be > 0 (seconds between frames)";
  }
  else if (numberOfFrames < 0)
  {
    text << "Number Of Frames = " << numberOfFrames << ": must be >= 0";
  }
  else if (!automatic && substepsPerFrame < 1)
  {
    text << "Substeps Per Frame = " << substepsPerFrame << ": must be >= 1";
  }
  else if (automatic && (!std::isfinite(maxTimeStep) || maxTimeStep <= 0.0))
  {
    text << "Max Time Step = " << maxTimeStep << ": must be > 0 (seconds)";
  }
  return text.str();
}
