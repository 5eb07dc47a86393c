// SPDX-License-Identifier: BSD-3-Clause
#include "FacePlanGather.h"

#include "vtkCellData.h"
#include "vtkDataSetAttributes.h"
#include "vtkDataSetAttributesFieldList.h"
#include "vtkExtractCells.h"
#include "vtkFieldData.h"
#include "vtkIdList.h"
#include "vtkIdTypeArray.h"
#include "vtkMergePoints.h"
#include "vtkMultiProcessController.h"
#include "vtkNew.h"
#include "vtkPointData.h"
#include "vtkPointSet.h"
#include "vtkPoints.h"
#include "vtkPolyData.h"
#include "vtkUnsignedCharArray.h"
#include "vtkUnstructuredGrid.h"

#include <algorithm>
#include <numeric>
#include <unordered_map>

namespace faceplan {
namespace gather {

namespace {

constexpr int kScatterTag = 72041;

bool IsGhostCell(vtkPointSet* piece, vtkIdType cell) {
  vtkUnsignedCharArray* ghosts = piece->GetCellData()->GetGhostArray();
  return ghosts && (ghosts->GetValue(cell) & vtkDataSetAttributes::DUPLICATECELL);
}

// Every non-empty piece has this kind of GlobalIds (points or cells).
template <class Attributes>
bool AllHaveGlobalIds(const std::vector<vtkSmartPointer<vtkPointSet>>& pieces,
                      Attributes attributes) {
  bool any = false;
  for (const auto& piece : pieces) {
    if (!piece || piece->GetNumberOfPoints() == 0)
      continue;
    if (!attributes(piece)->GetGlobalIds())
      return false;
    any = true;
  }
  return any;
}

vtkIdType GlobalId(vtkDataSetAttributes* attributes, vtkIdType i) {
  return static_cast<vtkIdType>(attributes->GetGlobalIds()->GetComponent(i, 0));
}

// The point ids that some non-ghost cell of the piece uses.
std::vector<char> UsedPoints(vtkPointSet* piece) {
  std::vector<char> used(static_cast<std::size_t>(piece->GetNumberOfPoints()), 0);
  vtkNew<vtkIdList> ids;
  for (vtkIdType c = 0; c < piece->GetNumberOfCells(); ++c) {
    if (IsGhostCell(piece, c))
      continue;
    piece->GetCellPoints(c, ids);
    for (vtkIdType k = 0; k < ids->GetNumberOfIds(); ++k)
      used[static_cast<std::size_t>(ids->GetId(k))] = 1;
  }
  return used;
}

void InsertCell(vtkPointSet* whole, int type, vtkIdList* ids) {
  if (auto* grid = vtkUnstructuredGrid::SafeDownCast(whole))
    grid->InsertNextCell(type, ids);
  else if (auto* poly = vtkPolyData::SafeDownCast(whole))
    poly->InsertNextCell(type, ids);
}

} // namespace

vtkMultiProcessController* DistributedController() {
  vtkMultiProcessController* controller = vtkMultiProcessController::GetGlobalController();
  return controller && controller->GetNumberOfProcesses() > 1 ? controller : nullptr;
}

bool LogsErrors() {
  vtkMultiProcessController* controller = DistributedController();
  return !controller || controller->GetLocalProcessId() == 0;
}

GatheredPieces::GatheredPieces(vtkMultiProcessController* controller, vtkPointSet* piece, int root)
    : Controller(controller), Root(root), Piece(piece) {
  // An unconnected input is unconnected on every rank: the gather still runs (it is collective),
  // and the root's Whole() stays null for the filter's own check to report.
  vtkNew<vtkUnstructuredGrid> nothing;
  std::vector<vtkSmartPointer<vtkDataObject>> received;
  controller->Gather(piece ? static_cast<vtkDataObject*>(piece) : nothing.Get(), received, root);
  if (!this->IsRoot() || !piece)
    return;

  const std::size_t nPieces = received.size();
  this->Pieces.resize(nPieces);
  for (std::size_t r = 0; r < nPieces; ++r)
    this->Pieces[r] = vtkPointSet::SafeDownCast(received[r]);
  this->Pieces[static_cast<std::size_t>(root)] = piece;

  const bool byPointIds =
      AllHaveGlobalIds(this->Pieces, [](vtkPointSet* p) { return p->GetPointData(); });
  const bool byCellIds =
      AllHaveGlobalIds(this->Pieces, [](vtkPointSet* p) { return p->GetCellData(); });

  // Points: (piece, point) pairs of the whole, one per distinct key, in key order.
  this->PointMap.assign(nPieces, {});
  std::vector<std::pair<std::size_t, vtkIdType>> source;
  std::vector<std::vector<char>> used(nPieces);
  for (std::size_t r = 0; r < nPieces; ++r) {
    vtkPointSet* p = this->Pieces[r];
    const vtkIdType n = p ? p->GetNumberOfPoints() : 0;
    this->PointMap[r].assign(static_cast<std::size_t>(n), -1);
    if (n > 0)
      used[r] = UsedPoints(p);
  }
  if (byPointIds) {
    std::vector<std::pair<vtkIdType, std::pair<std::size_t, vtkIdType>>> keyed;
    std::unordered_map<vtkIdType, vtkIdType> seen;
    for (std::size_t r = 0; r < nPieces; ++r)
      for (vtkIdType i = 0; i < static_cast<vtkIdType>(used[r].size()); ++i)
        if (used[r][static_cast<std::size_t>(i)]) {
          const vtkIdType gid = GlobalId(this->Pieces[r]->GetPointData(), i);
          if (seen.emplace(gid, 0).second)
            keyed.push_back({gid, {r, i}});
        }
    std::sort(keyed.begin(), keyed.end(),
              [](const auto& a, const auto& b) { return a.first < b.first; });
    for (std::size_t k = 0; k < keyed.size(); ++k) {
      seen[keyed[k].first] = static_cast<vtkIdType>(k);
      source.push_back(keyed[k].second);
    }
    for (std::size_t r = 0; r < nPieces; ++r)
      for (vtkIdType i = 0; i < static_cast<vtkIdType>(this->PointMap[r].size()); ++i) {
        auto it = seen.find(GlobalId(this->Pieces[r]->GetPointData(), i));
        if (it != seen.end())
          this->PointMap[r][static_cast<std::size_t>(i)] = it->second;
      }
  } else {
    double bounds[6] = {1, -1, 1, -1, 1, -1};
    for (const auto& p : this->Pieces)
      if (p && p->GetNumberOfPoints() > 0) {
        double b[6];
        p->GetBounds(b);
        for (int a = 0; a < 3; ++a) {
          bounds[2 * a] =
              bounds[2 * a] > bounds[2 * a + 1] ? b[2 * a] : std::min(bounds[2 * a], b[2 * a]);
          bounds[2 * a + 1] = std::max(bounds[2 * a + 1], b[2 * a + 1]);
        }
      }
    vtkNew<vtkPoints> merged;
    merged->SetDataTypeToDouble();
    vtkNew<vtkMergePoints> locator;
    locator->InitPointInsertion(merged, bounds);
    for (std::size_t r = 0; r < nPieces; ++r)
      for (vtkIdType i = 0; i < static_cast<vtkIdType>(used[r].size()); ++i)
        if (used[r][static_cast<std::size_t>(i)]) {
          double x[3];
          this->Pieces[r]->GetPoint(i, x);
          vtkIdType id;
          if (locator->InsertUniquePoint(x, id))
            source.push_back({r, i});
          this->PointMap[r][static_cast<std::size_t>(i)] = id;
        }
    for (std::size_t r = 0; r < nPieces; ++r)
      for (vtkIdType i = 0; i < static_cast<vtkIdType>(used[r].size()); ++i)
        if (!used[r][static_cast<std::size_t>(i)]) {
          double x[3];
          this->Pieces[r]->GetPoint(i, x);
          this->PointMap[r][static_cast<std::size_t>(i)] = locator->IsInsertedPoint(x);
        }
  }

  // The whole: points and point arrays from each point's first owner, then the cells.
  this->Whole_.TakeReference(piece->NewInstance());
  vtkPointSet* whole = this->Whole_;
  vtkDataSetAttributes::FieldList pointFields, cellFields;
  bool first = true;
  for (const auto& p : this->Pieces) {
    if (!p || p->GetNumberOfPoints() == 0)
      continue;
    if (first) {
      pointFields.InitializeFieldList(p->GetPointData());
      cellFields.InitializeFieldList(p->GetCellData());
      whole->GetFieldData()->ShallowCopy(p->GetFieldData());
      first = false;
    } else {
      pointFields.IntersectFieldList(p->GetPointData());
      cellFields.IntersectFieldList(p->GetCellData());
    }
  }
  vtkNew<vtkPoints> points;
  points->SetDataTypeToDouble();
  points->SetNumberOfPoints(static_cast<vtkIdType>(source.size()));
  whole->GetPointData()->CopyAllocate(pointFields, static_cast<vtkIdType>(source.size()));
  for (std::size_t k = 0; k < source.size(); ++k) {
    vtkPointSet* p = this->Pieces[source[k].first];
    points->SetPoint(static_cast<vtkIdType>(k), p->GetPoint(source[k].second));
    whole->GetPointData()->CopyData(pointFields, p->GetPointData(),
                                    static_cast<int>(source[k].first), source[k].second,
                                    static_cast<vtkIdType>(k));
  }
  whole->SetPoints(points);

  std::vector<std::pair<vtkIdType, std::pair<std::size_t, vtkIdType>>> cells;
  for (std::size_t r = 0; r < nPieces; ++r) {
    vtkPointSet* p = this->Pieces[r];
    if (!p || p->GetNumberOfPoints() == 0)
      continue;
    for (vtkIdType c = 0; c < p->GetNumberOfCells(); ++c)
      if (!IsGhostCell(p, c))
        cells.push_back(
            {byCellIds ? GlobalId(p->GetCellData(), c) : static_cast<vtkIdType>(cells.size()),
             {r, c}});
  }
  std::stable_sort(cells.begin(), cells.end(),
                   [](const auto& a, const auto& b) { return a.first < b.first; });
  if (auto* grid = vtkUnstructuredGrid::SafeDownCast(whole))
    grid->Allocate(static_cast<vtkIdType>(cells.size()));
  else if (auto* poly = vtkPolyData::SafeDownCast(whole))
    poly->AllocateEstimate(static_cast<vtkIdType>(cells.size()), 4);
  whole->GetCellData()->CopyAllocate(cellFields, static_cast<vtkIdType>(cells.size()));
  vtkNew<vtkIdList> ids;
  for (std::size_t k = 0; k < cells.size(); ++k) {
    const std::size_t r = cells[k].second.first;
    const vtkIdType c = cells[k].second.second;
    vtkPointSet* p = this->Pieces[r];
    p->GetCellPoints(c, ids);
    for (vtkIdType j = 0; j < ids->GetNumberOfIds(); ++j)
      ids->SetId(j, this->PointMap[r][static_cast<std::size_t>(ids->GetId(j))]);
    InsertCell(whole, p->GetCellType(c), ids);
    this->CellOwners.push_back(static_cast<int>(r));
    whole->GetCellData()->CopyData(cellFields, p->GetCellData(), static_cast<int>(r), c,
                                   static_cast<vtkIdType>(k));
  }
  // Ghost levels belong to the pieces, not to the whole.
  whole->GetPointData()->RemoveArray(vtkDataSetAttributes::GhostArrayName());
  whole->GetCellData()->RemoveArray(vtkDataSetAttributes::GhostArrayName());
}

bool GatheredPieces::IsRoot() const {
  return this->Controller->GetLocalProcessId() == this->Root;
}

void GatheredPieces::ScatterTo(vtkPointSet* wholeResult, vtkPointSet* output) const {
  // The carrier of one piece's result: points and point arrays, no cells.
  vtkNew<vtkPolyData> mine;
  if (this->IsRoot()) {
    for (std::size_t r = 0; r < this->PointMap.size(); ++r) {
      const std::vector<vtkIdType>& map = this->PointMap[r];
      vtkNew<vtkPolyData> carrier;
      vtkNew<vtkPoints> points;
      points->SetDataTypeToDouble();
      points->SetNumberOfPoints(static_cast<vtkIdType>(map.size()));
      vtkPointData* pd = carrier->GetPointData();
      pd->CopyAllocate(wholeResult->GetPointData(), static_cast<vtkIdType>(map.size()));
      for (vtkIdType i = 0; i < static_cast<vtkIdType>(map.size()); ++i) {
        const vtkIdType w = map[static_cast<std::size_t>(i)];
        if (w >= 0) {
          points->SetPoint(i, wholeResult->GetPoint(w));
          pd->CopyData(wholeResult->GetPointData(), w, i);
        } else { // used by ghost cells only: unmoved, null values
          points->SetPoint(i, this->Pieces[r]->GetPoint(i));
          pd->NullData(i);
        }
      }
      carrier->SetPoints(points);
      carrier->GetFieldData()->ShallowCopy(wholeResult->GetFieldData());
      if (static_cast<int>(r) == this->Root)
        mine->ShallowCopy(carrier);
      else
        this->Controller->Send(carrier, static_cast<int>(r), kScatterTag);
    }
  } else {
    this->Controller->Receive(mine, this->Root, kScatterTag);
  }

  if (!this->Piece) {
    output->Initialize();
    return;
  }
  output->ShallowCopy(this->Piece);
  if (this->Piece->GetNumberOfPoints() == 0) {
    output->GetFieldData()->ShallowCopy(mine->GetFieldData());
    return;
  }
  output->SetPoints(mine->GetPoints());
  vtkPointData* received = mine->GetPointData();
  for (int a = 0; a < received->GetNumberOfArrays(); ++a) {
    vtkAbstractArray* array = received->GetAbstractArray(a);
    if (array && array->GetName()) {
      output->GetPointData()->RemoveArray(array->GetName());
      output->GetPointData()->AddArray(array);
    }
  }
  if (vtkDataArray* vectors = received->GetVectors())
    output->GetPointData()->SetActiveVectors(vectors->GetName());
  output->GetFieldData()->ShallowCopy(mine->GetFieldData());
}

int GatheredPieces::CellOwner(vtkIdType wholeCell) const {
  return wholeCell >= 0 && wholeCell < static_cast<vtkIdType>(this->CellOwners.size())
             ? this->CellOwners[static_cast<std::size_t>(wholeCell)]
             : this->Root;
}

void GatheredPieces::ScatterCells(vtkUnstructuredGrid* wholeResult, const std::vector<int>& owner,
                                  vtkUnstructuredGrid* output) const {
  if (!this->IsRoot()) {
    this->Controller->Receive(output, this->Root, kScatterTag);
    return;
  }
  const int processes = this->Controller->GetNumberOfProcesses();
  std::vector<vtkNew<vtkIdList>> cells(static_cast<std::size_t>(processes));
  for (vtkIdType c = 0; c < static_cast<vtkIdType>(owner.size()); ++c)
    cells[static_cast<std::size_t>(owner[static_cast<std::size_t>(c)])]->InsertNextId(c);
  for (int r = 0; r < processes; ++r) {
    vtkNew<vtkExtractCells> extract;
    extract->SetInputData(wholeResult);
    extract->SetCellList(cells[static_cast<std::size_t>(r)]);
    extract->Update();
    vtkUnstructuredGrid* part = extract->GetOutput();
    part->GetFieldData()->ShallowCopy(wholeResult->GetFieldData());
    if (r == this->Root)
      output->ShallowCopy(part);
    else
      this->Controller->Send(part, r, kScatterTag);
  }
}

std::string ShareRootMessage(vtkMultiProcessController* controller, int root,
                             const std::string& message) {
  vtkIdType length = static_cast<vtkIdType>(message.size());
  controller->Broadcast(&length, 1, root);
  std::string shared(static_cast<std::size_t>(length), '\0');
  if (controller->GetLocalProcessId() == root)
    shared = message;
  if (length > 0)
    controller->Broadcast(&shared[0], length, root);
  return shared;
}

void BroadcastFromRoot(vtkMultiProcessController* controller, int root, vtkDataObject* data) {
  controller->Broadcast(data, root);
}

bool RunOnWhole(vtkMultiProcessController* controller, vtkPointSet* piece, vtkPointSet* output,
                const RunWhole& run) {
  constexpr int root = 0;
  const GatheredPieces pieces(controller, piece, root);
  vtkSmartPointer<vtkPointSet> wholeOutput;
  std::string failure;
  if (pieces.IsRoot()) {
    if (!pieces.Whole())
      failure = "no input";
    else {
      wholeOutput.TakeReference(pieces.Whole()->NewInstance());
      if (!run(pieces.Whole(), wholeOutput))
        failure = "failed on rank 0";
    }
  }
  if (!ShareRootMessage(controller, root, failure).empty()) {
    output->Initialize();
    return false;
  }
  pieces.ScatterTo(wholeOutput, output);
  return true;
}

} // namespace gather
} // namespace faceplan
