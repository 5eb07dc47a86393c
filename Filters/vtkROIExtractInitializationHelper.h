// SPDX-License-Identifier: BSD-3-Clause
/**
 * @class vtkROIExtractInitializationHelper
 * @brief Places a new ROI Extract proxy's sphere on the bone where an operation would be planned.
 *
 * ParaView's Sphere starts from the input's bounds: centred in the bounding box with half its
 * largest extent as radius, which marks the whole bone (and, in pvpython before the input was
 * updated, with radius -1). Named in Plugin/ROIExtract.xml's hints, this helper runs when the GUI
 * or paraview.simple creates the proxy and sets the Sphere's Center and Radius to the filter's
 * DefaultSphere (vtkROIExtract::GetDefaultSphere), unless they were set while the proxy was
 * created. Client side only; the filter itself does not depend on it.
 */
#ifndef vtkROIExtractInitializationHelper_h
#define vtkROIExtractInitializationHelper_h

#include "FacePlanFiltersModule.h"
#include "vtkSMProxyInitializationHelper.h"

class FACEPLANFILTERS_EXPORT vtkROIExtractInitializationHelper
    : public vtkSMProxyInitializationHelper {
public:
  static vtkROIExtractInitializationHelper* New();
  vtkTypeMacro(vtkROIExtractInitializationHelper, vtkSMProxyInitializationHelper);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  void PostInitializeProxy(vtkSMProxy* proxy, vtkPVXMLElement* xml,
                           vtkMTimeType initializationTimeStamp) override;

protected:
  vtkROIExtractInitializationHelper() = default;
  ~vtkROIExtractInitializationHelper() override = default;

private:
  vtkROIExtractInitializationHelper(const vtkROIExtractInitializationHelper&) = delete;
  void operator=(const vtkROIExtractInitializationHelper&) = delete;
};

#endif
