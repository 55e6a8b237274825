#include "vtkPBFPortDemand.h"

#include "vtkAlgorithm.h"
#include "vtkDataObject.h"
#include "vtkExecutive.h"
#include "vtkInformation.h"
#include "vtkInformationExecutivePortVectorKey.h"
#include "vtkInformationVector.h"
#include "vtkStreamingDemandDrivenPipeline.h"

namespace
{

// True when nobody downstream of the port will look at its data: its only consumers are
// ParaView's per-port post filters (vtkPVPostFilter, which every source proxy puts after each
// of its output ports) with no consumer of their own. A proxy's UpdatePipeline(), which Apply
// calls, updates every port through them; a view, a filter, a writer or a Fetch hangs below
// them. A port with no consumer at all is asked directly (Update(port) in C++) and is wanted.
bool OnlyUnwatchedPostFilters(vtkAlgorithm* algorithm, int port)
{
  vtkInformation* info = algorithm->GetExecutive()->GetOutputInformation(port);
  vtkInformationExecutivePortVectorKey* consumers = vtkExecutive::CONSUMERS();
  const int count = info && info->Has(consumers) ? consumers->Length(info) : 0;
  vtkExecutive** executives = count > 0 ? consumers->GetExecutives(info) : nullptr;
  for (int c = 0; c < count; ++c)
  {
    vtkAlgorithm* consumer = executives[c] ? executives[c]->GetAlgorithm() : nullptr;
    if (!consumer || !consumer->IsA("vtkPVPostFilter"))
    {
      return false;
    }
    for (int p = 0; p < consumer->GetNumberOfOutputPorts(); ++p)
    {
      vtkInformation* below = consumer->GetExecutive()->GetOutputInformation(p);
      if (below && below->Has(consumers) && consumers->Length(below) > 0)
      {
        return false;
      }
    }
  }
  return count > 0;
}

// True when port 0 already holds the frame at frameTime and nothing upstream or in the algorithm
// changed since it was made (the executive's own test of an output's age).
bool ParticlesCurrent(vtkAlgorithm* algorithm, vtkInformationVector* outputVector, double frameTime)
{
  auto* executive = vtkStreamingDemandDrivenPipeline::SafeDownCast(algorithm->GetExecutive());
  vtkDataObject* particles = outputVector->GetInformationObject(0)->Get(vtkDataObject::DATA_OBJECT());
  if (!executive || !particles)
  {
    return false;
  }
  vtkInformation* info = particles->GetInformation();
  return info->Has(vtkDataObject::DATA_TIME_STEP()) &&
    info->Get(vtkDataObject::DATA_TIME_STEP()) == frameTime &&
    particles->GetUpdateTime() > executive->GetPipelineMTime();
}

} // namespace

//------------------------------------------------------------------------------
vtkPBFPortDemand vtkPBFPortDemand::Of(vtkAlgorithm* algorithm, vtkInformation* request,
  vtkInformationVector* outputVector, int surfacePort, bool keepSurface, bool frameHeld,
  double frameTime)
{
  const int from = request->Has(vtkDemandDrivenPipeline::FROM_OUTPUT_PORT())
    ? request->Get(vtkDemandDrivenPipeline::FROM_OUTPUT_PORT())
    : 0;
  vtkPBFPortDemand demand;
  const bool surfaceAsked = from == surfacePort && !OnlyUnwatchedPostFilters(algorithm, surfacePort);
  demand.Surface = keepSurface || surfaceAsked;
  // A request through the surface's port for the frame already on port 0 makes the surface
  // alone: the particles' consumers see no new data and do not execute again.
  if (from == surfacePort && frameHeld && ParticlesCurrent(algorithm, outputVector, frameTime))
  {
    demand.Frame = false;
  }
  return demand;
}

//------------------------------------------------------------------------------
void vtkPBFPortDemand::MarkNotGenerated(vtkInformationVector* outputVector, int surfacePort) const
{
  for (int port = 0; port < outputVector->GetNumberOfInformationObjects(); ++port)
  {
    if (port == surfacePort ? !this->Surface : !this->Frame)
    {
      outputVector->GetInformationObject(port)->Set(vtkDemandDrivenPipeline::DATA_NOT_GENERATED(), 1);
    }
  }
}
