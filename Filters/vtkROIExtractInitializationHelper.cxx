// SPDX-License-Identifier: BSD-3-Clause
#include "vtkROIExtractInitializationHelper.h"

#include "vtkObjectFactory.h"
#include "vtkSMPropertyHelper.h"
#include "vtkSMProxy.h"
#include "vtkSMProxyListDomain.h"
#include "vtkSMProxyProperty.h"

#include <cmath>

vtkStandardNewMacro(vtkROIExtractInitializationHelper);

void vtkROIExtractInitializationHelper::PostInitializeProxy(vtkSMProxy* proxy, vtkPVXMLElement*,
                                                            vtkMTimeType initializationTimeStamp) {
  vtkSMProperty* region = proxy ? proxy->GetProperty("Region") : nullptr;
  auto* domain = region ? region->FindDomain<vtkSMProxyListDomain>() : nullptr;
  vtkSMProxy* sphere = domain ? domain->FindProxy("implicit_functions", "Sphere") : nullptr;
  vtkSMProperty* center = sphere ? sphere->GetProperty("Center") : nullptr;
  vtkSMProperty* radius = sphere ? sphere->GetProperty("Radius") : nullptr;
  vtkSMProperty* defaults = proxy ? proxy->GetProperty("DefaultSphere") : nullptr;
  if (!center || !radius || !defaults)
    return;
  // Values given while the proxy was created (pvpython keyword arguments) win.
  if (center->GetMTime() > initializationTimeStamp || radius->GetMTime() > initializationTimeStamp)
    return;
  proxy->UpdatePropertyInformation(defaults);
  vtkSMPropertyHelper placed(defaults);
  if (placed.GetNumberOfElements() != 4 || !(placed.GetAsDouble(3) > 0.0) ||
      !std::isfinite(placed.GetAsDouble(3)))
    return;
  const double c[3] = {placed.GetAsDouble(0), placed.GetAsDouble(1), placed.GetAsDouble(2)};
  vtkSMPropertyHelper(center).Set(c, 3);
  vtkSMPropertyHelper(radius).Set(placed.GetAsDouble(3));
  sphere->UpdateVTKObjects();
}

void vtkROIExtractInitializationHelper::PrintSelf(ostream& os, vtkIndent indent) {
  this->Superclass::PrintSelf(os, indent);
}
