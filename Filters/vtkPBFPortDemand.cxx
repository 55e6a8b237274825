#include "vtkPBFPortDemand.h"

#include "vtkAlgorithm.h"
#include "vtkDataObject.h"
#include "vtkExecutive.h"
#include "vtkInformation.h"
#include "vtkInformationExecutivePortVectorKey.h"
#include "vtkInformationVector.h"
#include "vtkStreamingDemandDrivenPipeline.h"

#include <algorithm>

namespace
{

// ParaView's plumbing below every output port of a source proxy: the post filter
// (vtkPVPostFilter, through which the proxy's UpdatePipeline, and so Apply, updates each port)
// and the selection extractor that a shown representation hangs beside it (vtkPVExtractSelection).
// Neither looks at the data unless something hangs below it in turn.
bool IsPlumbing(vtkAlgorithm* algorithm)
{
  return algorithm->IsA("vtkPVPostFilter") || algorithm->IsA("vtkPVExtractSelection");
}

// The consumers of an algorithm's output port.
int ConsumersOf(vtkAlgorithm* algorithm, int port, vtkExecutive**& executives)
{
  vtkInformation* info = algorithm->GetExecutive()->GetOutputInformation(port);
  vtkInformationExecutivePortVectorKey* consumers = vtkExecutive::CONSUMERS();
  const int count = info && info->Has(consumers) ? consumers->Length(info) : 0;
  executives = count > 0 ? consumers->GetExecutives(info) : nullptr;
  return count;
}

// True when something below the port looks at its data: a view's representation, a filter, a
// writer, a Fetch, found through ParaView's plumbing.
bool Watched(vtkAlgorithm* algorithm, int port)
{
  vtkExecutive** executives = nullptr;
  const int count = ConsumersOf(algorithm, port, executives);
  for (int c = 0; c < count; ++c)
  {
    vtkAlgorithm* consumer = executives[c] ? executives[c]->GetAlgorithm() : nullptr;
    if (!consumer)
    {
      continue;
    }
    if (!IsPlumbing(consumer))
    {
      return true;
    }
    for (int p = 0; p < consumer->GetNumberOfOutputPorts(); ++p)
    {
      if (Watched(consumer, p))
      {
        return true;
      }
    }
  }
  return false;
}

// True when a request through the port comes from someone who wants its data: the port is
// watched, or it has no consumer at all (asked directly, Update(port) in C++).
bool Wanted(vtkAlgorithm* algorithm, int port)
{
  vtkExecutive** executives = nullptr;
  return ConsumersOf(algorithm, port, executives) == 0 || Watched(algorithm, port);
}

// True when port 0 already holds the frame at frameTime and neither the algorithm nor anything
// upstream changed since it was made (the executive's own test of an output's age, without the
// surface's stamp, which ComputePipelineMTime may have moved for port 3 alone).
bool ParticlesCurrent(vtkAlgorithm* algorithm, vtkInformationVector* outputVector, double frameTime)
{
  vtkDataObject* particles = outputVector->GetInformationObject(0)->Get(vtkDataObject::DATA_OBJECT());
  if (!particles)
  {
    return false;
  }
  vtkMTimeType upstream = algorithm->GetMTime();
  for (int port = 0; port < algorithm->GetNumberOfInputPorts(); ++port)
  {
    for (int c = 0; c < algorithm->GetNumberOfInputConnections(port); ++c)
    {
      vtkAlgorithm* input = algorithm->GetInputAlgorithm(port, c);
      auto* executive = input ? vtkDemandDrivenPipeline::SafeDownCast(input->GetExecutive()) : nullptr;
      upstream = executive ? std::max(upstream, executive->GetPipelineMTime()) : upstream;
    }
  }
  vtkInformation* info = particles->GetInformation();
  return info->Has(vtkDataObject::DATA_TIME_STEP()) &&
    info->Get(vtkDataObject::DATA_TIME_STEP()) == frameTime && particles->GetUpdateTime() > upstream;
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
  const bool surfaceAsked = from == surfacePort && Wanted(algorithm, surfacePort);
  demand.Surface = keepSurface || surfaceAsked;
  demand.LeftStale = from == surfacePort && !demand.Surface;
  // A request through the surface's port makes the frame only when the surface needs it: nobody
  // watching the surface leaves everything as it is (the frame is port 0's request's business,
  // and a failed one is not run again), and a frame already on port 0 gives the surface alone
  // (the particles' consumers see no new data and do not execute again).
  if (from == surfacePort &&
    (!demand.Surface || (frameHeld && ParticlesCurrent(algorithm, outputVector, frameTime))))
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
