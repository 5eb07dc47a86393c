# SPDX-License-Identifier: BSD-3-Clause
"""One run of the MPI TissueModelFromCT test (pvbatch, serial or under mpiexec): the head CT's
model, its tissue points and cell count saved from the first process, which holds the model.

    pvbatch RunTissueModel.py <FacePlan.so> <CT .vti> <out.npz>
"""
import sys

import numpy as np
from paraview import servermanager
from paraview.simple import LoadPlugin, XMLImageDataReader
from vtkmodules.util.numpy_support import vtk_to_numpy

plugin, ct_file, out_file = sys.argv[1:4]
LoadPlugin(plugin, ns=globals())
model = TissueModelFromCT(Input=XMLImageDataReader(FileName=[ct_file]), CellSize=10.0,
                          SurfaceDistance=2.5)
model.UpdatePipeline()
tissue = servermanager.Fetch(model)  # the first process's output: the whole model
np.savez(out_file, points=vtk_to_numpy(tissue.GetPoints().GetData()),
         cells=np.array(tissue.GetNumberOfCells()),
         total_points=np.array(model.GetDataInformation().GetNumberOfPoints()))
print("TissueModelFromCT: %d points, %d cells" % (tissue.GetNumberOfPoints(), tissue.GetNumberOfCells()))
