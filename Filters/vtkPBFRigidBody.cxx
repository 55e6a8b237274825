#include "vtkPBFRigidBody.h"

#include "vtkDataObject.h"
#include "vtkDoubleArray.h"
#include "vtkFieldData.h"
#include "vtkInformation.h"
#include "vtkInformationVector.h"
#include "vtkNew.h"
#include "vtkObjectFactory.h"
#include "vtkStringArray.h"

vtkStandardNewMacro(vtkPBFRigidBody);

//------------------------------------------------------------------------------
vtkPBFRigidBody::vtkPBFRigidBody()
  : Density(500.0)
  , Name(nullptr)
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
}
