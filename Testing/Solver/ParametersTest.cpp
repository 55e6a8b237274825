// Bad parameters are rejected with a message naming the field and the value; the parameter
// table's rows are consistent.
#include "ParameterTable.h"
#include "Parameters.h"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <limits>
#include <set>
#include <string>

using pbf::findParameter;
using pbf::InvalidInput;
using pbf::ParameterSpec;
using pbf::ParameterType;
using pbf::Parameters;
using pbf::parameterTable;
using pbf::sameTableParameters;

namespace
{

void expectRejected(std::function<void(Parameters&)> change, const std::string& field,
  const std::string& value)
{
  Parameters p;
  change(p);
  try
  {
    p.validate();
    FAIL() << field << " was accepted";
  }
  catch (const InvalidInput& error)
  {
    const std::string message = error.what();
    EXPECT_NE(message.find(field), std::string::npos) << message;
    EXPECT_NE(message.find(value), std::string::npos) << message;
  }
}

} // namespace

TEST(Parameters, DefaultsAreValid)
{
  EXPECT_NO_THROW(Parameters().validate());
}

TEST(Parameters, BadValuesNameTheFieldAndTheValue)
{
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  expectRejected([](Parameters& p) { p.particleSpacing = 0; }, "particleSpacing", "0");
  expectRejected([](Parameters& p) { p.particleSpacing = -0.01; }, "particleSpacing", "-0.01");
  expectRejected([&](Parameters& p) { p.restDensity = nan; }, "restDensity", "nan");
  expectRejected([&](Parameters& p) { p.timeStep = inf; }, "timeStep", "inf");
  expectRejected([](Parameters& p) { p.smoothingRatio = 0.5; }, "smoothingRatio", "0.5");
  // At exactly 1 the lattice neighbours sit at h, outside the support: no neighbour at all.
  expectRejected([](Parameters& p) { p.smoothingRatio = 1.0; }, "smoothingRatio", "1");
  expectRejected([](Parameters& p) { p.solverIterations = 0; }, "solverIterations", "0");
  expectRejected([](Parameters& p) { p.solverIterations = -3; }, "solverIterations", "-3");
  expectRejected([](Parameters& p) { p.relaxation = 0; }, "relaxation", "0");
  expectRejected([](Parameters& p) { p.sCorrDeltaQ = 1.5; }, "sCorrDeltaQ", "1.5");
  expectRejected([](Parameters& p) { p.xsphViscosity = -1; }, "xsphViscosity", "-1");
  expectRejected([](Parameters& p) { p.xsphHyperViscosity = -1; }, "xsphHyperViscosity", "-1");
  expectRejected([](Parameters& p) { p.xsphHyperViscosity = 2; }, "xsphHyperViscosity", "2");
  expectRejected([](Parameters& p) { p.chebyshevRho = -0.5; }, "chebyshevRho", "-0.5");
  expectRejected([](Parameters& p) { p.chebyshevRho = 1; }, "chebyshevRho", "1");
  expectRejected([](Parameters& p) { p.cflNumber = 0; }, "cflNumber", "0");
  expectRejected([](Parameters& p) { p.cflNumber = 1.5; }, "cflNumber", "1.5");
  expectRejected([&](Parameters& p) { p.gravity.y = nan; }, "gravity.y", "nan");
  expectRejected([](Parameters& p) { p.domain.max.x = 0.01; }, "domain.max.x", "0.01");
}

TEST(Parameters, CalibratedMassMakesTheLatticeReadRestDensity)
{
  Parameters p;
  // With m = rho_0 s^3 the lattice reads about 1% high at h = 2 s:
  // the calibrated mass must differ from it by that much, and in the right direction.
  const double naive = p.restDensity * std::pow(p.particleSpacing, 3);
  const double calibrated = pbf::calibratedParticleMass(p);
  EXPECT_LT(calibrated, naive);
  EXPECT_GT(calibrated, 0.95 * naive);
}

TEST(ParameterTable, RowsAreUniqueTheirDefaultsValidAndTheirSlidersInRange)
{
  // Every name a row gives is used by one row only (a property, a field-data array and an
  // option each name one parameter); the default and both slider ends lie in the valid range,
  // so the GUI never offers a value the solver refuses; get and set address the same member.
  std::set<std::string> fields, properties, options;
  for (const ParameterSpec& spec : parameterTable())
  {
    EXPECT_TRUE(fields.insert(spec.field).second) << spec.field;
    EXPECT_TRUE(properties.insert(spec.property).second) << spec.property;
    EXPECT_TRUE(options.insert(spec.option).second) << spec.option;
    EXPECT_EQ(findParameter(spec.field), &spec);
    EXPECT_EQ(findParameter(spec.property), &spec);
    EXPECT_GT(std::string(spec.help).size(), 20u) << spec.property;
    for (int c = 0; c < spec.components(); ++c)
    {
      EXPECT_TRUE(spec.valid.contains(spec.defaultValue(c))) << spec.property;
      EXPECT_TRUE(spec.valid.contains(spec.sliderMin)) << spec.property << " " << spec.sliderMin;
      EXPECT_TRUE(spec.valid.contains(spec.sliderMax)) << spec.property << " " << spec.sliderMax;
      Parameters p;
      const double other = spec.type == ParameterType::Boolean
        ? 1.0 - spec.defaultValue(c)
        : spec.sliderMin + 0.25 * (spec.sliderMax - spec.sliderMin);
      spec.set(p, c, other);
      EXPECT_EQ(spec.get(p, c), spec.type == ParameterType::Integer ? std::trunc(other) : other)
        << spec.property;
      EXPECT_FALSE(sameTableParameters(p, Parameters())) << spec.property;
    }
  }
  EXPECT_EQ(findParameter("noSuchParameter"), nullptr);
}

TEST(ParameterTable, AValueOutsideItsRangeNamesTheFieldTheValueAndTheRange)
{
  Parameters p;
  p.smoothingRatio = 1.0;
  try
  {
    p.validate();
    FAIL() << "smoothingRatio = 1 was accepted";
  }
  catch (const InvalidInput& error)
  {
    EXPECT_EQ(std::string(error.what()),
      "smoothingRatio = 1: must lie in (1, 4] (h / spacing at 1 or less leaves a particle no "
      "neighbour within h)");
  }
}
