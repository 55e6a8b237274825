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
  // Only data representations that can draw Point Gaussians (render views) have both.
  if (!display || !display->GetProperty("Input") || !display->GetProperty("GaussianRadius"))
  {
    return;
  }
  vtkSMProxy* producer = vtkSMPropertyHelper(display, "Input", /*quiet=*/true).GetAsProxy();
  if (!producer || !producer->GetVTKClassName() ||
    std::strcmp(producer->GetVTKClassName(), "vtkPBFSimulation") != 0)
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
