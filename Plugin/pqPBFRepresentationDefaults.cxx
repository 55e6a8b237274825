#include "pqPBFRepresentationDefaults.h"

#include "pqApplicationCore.h"
#include "pqRepresentation.h"
#include "pqServerManagerModel.h"
#include "vtkNew.h"
#include "vtkSMPropertyHelper.h"
#include "vtkSMProxy.h"
#include "vtkSMSessionProxyManager.h"
#include "vtkSMTransferFunctionManager.h"

#include <cstring>

//------------------------------------------------------------------------------
pqPBFRepresentationDefaults::pqPBFRepresentationDefaults(QObject* parent)
  : Superclass(parent)
{
}

//------------------------------------------------------------------------------
pqPBFRepresentationDefaults::~pqPBFRepresentationDefaults() = default;

//------------------------------------------------------------------------------
void pqPBFRepresentationDefaults::startup()
{
  pqServerManagerModel* model = pqApplicationCore::instance()->getServerManagerModel();
  QObject::connect(model, &pqServerManagerModel::representationAdded, this,
    &pqPBFRepresentationDefaults::onRepresentationAdded);
}

//------------------------------------------------------------------------------
void pqPBFRepresentationDefaults::shutdown()
{
  pqServerManagerModel* model = pqApplicationCore::instance()->getServerManagerModel();
  QObject::disconnect(model, nullptr, this, nullptr);
}

//------------------------------------------------------------------------------
void pqPBFRepresentationDefaults::onRepresentationAdded(pqRepresentation* representation)
{
  vtkSMProxy* display = representation ? representation->getProxy() : nullptr;
  if (!display || !display->GetProperty("Input"))
  {
    return;
  }
  vtkSMPropertyHelper input(display, "Input", /*quiet=*/true);
  vtkSMProxy* producer = input.GetAsProxy();
  if (!producer || !producer->GetVTKClassName() ||
    std::strcmp(producer->GetVTKClassName(), "vtkPBFSimulation") != 0)
  {
    return;
  }
  // The diagnostics (port 1) in a chart: against Time (ParaView's default X array when a column
  // has that name), the two density errors only, both in percent; the other columns are on
  // other scales and one click away in the series list.
  if (input.GetOutputPort() == 1 && display->GetProperty("SeriesVisibility"))
  {
    static const char* const columns[] = { "AverageDensityError", "MaxDensityError",
      "AverageNeighbors", "SolverIterations", "MillisecondsPerStep", "Substeps", "MinTimeStep",
      "MaxTimeStep", "MaxSpeed", "KineticEnergy", "Frame", "Particles" };
    vtkSMPropertyHelper visibility(display, "SeriesVisibility");
    unsigned int element = 0;
    for (const char* column : columns)
    {
      const bool shown = std::strcmp(column, "AverageDensityError") == 0 ||
        std::strcmp(column, "MaxDensityError") == 0;
      visibility.Set(element++, column);
      visibility.Set(element++, shown ? "1" : "0");
    }
    display->UpdateVTKObjects();
    return;
  }
  // Only data representations that can draw Point Gaussians (render views) have a radius.
  if (!display->GetProperty("GaussianRadius"))
  {
    return;
  }

  const double spacing = vtkSMPropertyHelper(producer, "ParticleSpacing").GetAsDouble();
  vtkSMPropertyHelper(display, "GaussianRadius").Set(0.5 * spacing);
  display->UpdateVTKObjects();

  // The color map is the session's one for arrays named "velocity", the one Show picks.
  vtkNew<vtkSMTransferFunctionManager> manager;
  if (vtkSMProxy* colors =
        manager->GetColorTransferFunction("velocity", display->GetSessionProxyManager()))
  {
    vtkSMPropertyHelper(colors, "AutomaticRescaleRangeMode")
      .Set(vtkSMTransferFunctionManager::GROW_ON_APPLY_AND_TIMESTEP);
    colors->UpdateVTKObjects();
  }
}
