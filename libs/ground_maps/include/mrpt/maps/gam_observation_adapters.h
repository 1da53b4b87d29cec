// Ground-aware mapping for MRPT
// Glue between MRPT observations and the pure ground_core algorithms: turns
// observations into BinnedPoints of an ElevationGrid.
#pragma once

#include <mrpt/maps/COccupancyGridMap2D.h>
#include <mrpt/maps/CPointsMap.h>
#include <mrpt/obs/CObservation.h>
#include <mrpt/obs/CObservation2DRangeScan.h>
#include <mrpt/obs/CObservation3DRangeScan.h>
#include <mrpt/poses/CPose3D.h>

#include "gam/DepthProjector.h"
#include "gam/ElevationGrid.h"

namespace gam::mrpt_glue
{
/** CPose3D -> rigid transform (rotation + translation) in floats. */
RigidTransform toRigid(const mrpt::poses::CPose3D& p);

/** Intrinsics of the depth camera of a 3D scan. */
PinholeIntrinsics intrinsicsOf(const mrpt::obs::CObservation3DRangeScan& o);

/** Which points go into the 2.5D grid. Heights are in the grid (map) frame. */
struct BinningOptions
{
	ProjectionFilter filter;
	/** true: a depth/range beyond the observation's own maxRange is dropped too. */
	bool use_observation_max_range = true;
};

/** Bins any supported observation taken from `robotPose` into `grid` bins:
 * CObservation3DRangeScan (from its range image, or its points3D if it has no
 * range image), CObservation2DRangeScan, CObservationPointCloud.
 * Returns false if the class is not supported; throws std::invalid_argument
 * (with a message naming the field) for malformed observations. */
bool binObservation(
	const mrpt::obs::CObservation& obs, const mrpt::poses::CPose3D& robotPose,
	const BinningOptions& opts, const ElevationGrid& grid, DepthProjector& projector,
	BinnedPoints& out, size_t* pointsBinned = nullptr);

/** Bins a point cloud given in the frame `pose` (points are first mapped by it). */
size_t binPointCloud(
	const mrpt::maps::CPointsMap& pts, const mrpt::poses::CPose3D& pose,
	const ProjectionFilter& f, const ElevationGrid& grid, BinnedPoints& out);

/** Checks a 3D scan before it reaches MRPT code that trusts it (the comparison
 * maps hand it to convertTo2DScan() / unprojectInto()): finite sensorPose; for a
 * range image, intrinsics (PinholeIntrinsics::validate), image size = cameraParams
 * size and rangeUnits > 0; for points3D, equal x/y/z sizes. Throws
 * std::invalid_argument naming the field. */
void checkRangeScan(const mrpt::obs::CObservation3DRangeScan& o);

/** Largest 2D occupancy grid any map of this plugin creates or grows to:
 * 2^28 cells (256 MiB of 8-bit cells; MRPT keeps more per cell for some
 * operations). A .ini extent or a robot pose that needs more is an error. */
constexpr double kMaxGridCells = double(1u << 28);

/** Throws std::invalid_argument ("<what>: a grid of NxM cells ... is too large")
 * if [x0,x1]x[y0,y1] at `resolution` needs more than kMaxGridCells cells, or if
 * any value is not finite. */
void checkGridSize(const std::string& what, double x0, double x1, double y0, double y1, double resolution);

/** Before MRPT's beam model inserts a 2D scan taken at `sensorInMap` into `g`
 * (it grows the grid to hold the rays, up to insertionOptions.maxDistanceInsertion):
 * throws std::invalid_argument if the pose is not finite or if the grown grid would
 * exceed kMaxGridCells (a robot pose far from everything seen so far). */
void checkScanGrowth(
	const mrpt::maps::COccupancyGridMap2D& g, const mrpt::poses::CPose3D& sensorInMap, double farthestRange = 0);

/** A copy of `in` that MRPT's beam model can take safely (it grows the grid to
 * every valid range, computing the new size in 32-bit ints: a 1e30 m range became
 * a heap overflow in resizeGrid(), found by tests/fuzz/fuzz_rawlog): ranges that
 * are not finite, <= 0 or beyond the scan's maxRange are marked invalid, and the
 * growth to the farthest remaining one is checked (checkScanGrowth). Throws
 * std::invalid_argument for a non-finite aperture or maxRange, or a too large grid. */
mrpt::obs::CObservation2DRangeScan safeScanFor(
	const mrpt::maps::COccupancyGridMap2D& g, const mrpt::obs::CObservation2DRangeScan& in,
	const mrpt::poses::CPose3D& robotPose);

}  // namespace gam::mrpt_glue
