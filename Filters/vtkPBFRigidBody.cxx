#include "vtkPBFRigidBody.h"

#include "vtkDataObject.h"
#include "vtkDoubleArray.h"
#include "vtkFieldData.h"
#include "vtkInformation.h"
#include "vtkInformationVector.h"
#include "vtkIntArray.h"
#include "vtkNew.h"
#include "vtkObjectFactory.h"
#include "vtkStringArray.h"

vtkStandardNewMacro(vtkPBFRigidBody);

//------------------------------------------------------------------------------
vtkPBFRigidBody::vtkPBFRigidBody()
  : Density(500.0)
  , Name(nullptr)
  , FreeAxes{ 1, 1, 1 }
  , Turns(true)
  , Release(0.0)
{
}

//------------------------------------------------------------------------------
vtkPBFRigidBody::~vtkPBFRigidBody()
{
  this->SetName(nullptr);
}

//------------------------------------------------------------------------------
int vtkPBFRigidBody::RequestData(
  vtkInformation*, vtkInformationVector** inputVector, vtkInformationVector* outputVector)
{
  vtkDataObject* input = vtkDataObject::GetData(inputVector[0]);
  vtkDataObject* output = vtkDataObject::GetData(outputVector);
  output->ShallowCopy(input);
  // A field data of its own: the input's stays as it was.
  vtkNew<vtkFieldData> fields;
  fields->ShallowCopy(input->GetFieldData());
  vtkNew<vtkDoubleArray> density;
  density->SetName("PBFBodyDensity");
  density->InsertNextValue(this->Density);
  fields->AddArray(density);
  vtkNew<vtkIntArray> axes;
  axes->SetName("PBFBodyFreeAxes");
  axes->SetNumberOfComponents(3);
  axes->InsertNextTypedTuple(this->FreeAxes);
  fields->AddArray(axes);
  vtkNew<vtkIntArray> turns;
  turns->SetName("PBFBodyTurns");
  turns->InsertNextValue(this->Turns ? 1 : 0);
  fields->AddArray(turns);
  vtkNew<vtkDoubleArray> release;
  release->SetName("PBFBodyRelease");
  release->InsertNextValue(this->Release);
  fields->AddArray(release);
  if (this->Name && *this->Name)
  {
    vtkNew<vtkStringArray> name;
    name->SetName("PBFBodyName");
    name->InsertNextValue(this->Name);
    fields->AddArray(name);
  }
  output->SetFieldData(fields);
  return 1;
}

//------------------------------------------------------------------------------
void vtkPBFRigidBody::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  os << indent << "Density: " << this->Density << "\n";
  os << indent << "Name: " << (this->Name ? this->Name : "(none)") << "\n";
  os << indent << "FreeAxes: " << this->FreeAxes[0] << " " << this->FreeAxes[1] << " "
     << this->FreeAxes[2] << "\n";
  os << indent << "Turns: " << this->Turns << "\n";
  os << indent << "Release: " << this->Release << "\n";
}
