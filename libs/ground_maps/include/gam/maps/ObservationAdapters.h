// Ground-aware mapping for MRPT
// Glue between MRPT observations and the pure ground_core algorithms: an
// observation becomes a gam::SensorFrame (no copy of its samples), and the
// checks that keep malformed observations and poses away from MRPT code.
#pragma once

#include <mrpt/maps/COccupancyGridMap2D.h>
#include <mrpt/maps/CPointsMap.h>
#include <mrpt/obs/CObservation.h>
#include <mrpt/obs/CObservation2DRangeScan.h>
#include <mrpt/obs/CObservation3DRangeScan.h>
#include <mrpt/poses/CPose3D.h>

#include "gam/core/DepthProjector.h"
#include "gam/core/ElevationGrid.h"
#include "gam/core/SensorFrame.h"

namespace gam::maps
{
/** CPose3D -> rigid transform (rotation + translation) in floats. */
RigidTransform toRigid(const mrpt::poses::CPose3D& p);

/** Intrinsics of the depth camera of a 3D scan. */
PinholeIntrinsics intrinsicsOf(const mrpt::obs::CObservation3DRangeScan& o);

/** Adapts a CObservation3DRangeScan (its range image, or its points3D if it
 * has no range image) or a CObservationPointCloud taken from `robotPose`:
 * the samples (referenced, not copied: `obs` must outlive `out`), the sensor
 * pose in the map frame and the observation's own maxRange. Returns false for
 * other classes; throws std::invalid_argument (naming the field) for
 * non-finite poses and malformed observations. */
bool toSensorFrame(const mrpt::obs::CObservation& obs, const mrpt::poses::CPose3D& robotPose, SensorFrame& out);

/** Places `out`'s sensor at `sensorInMap` (the robot pose composed with a
 * sensor pose on the robot), e.g. a measured mount instead of the declared one. */
void placeSensor(const mrpt::poses::CPose3D& sensorInMap, SensorFrame& out);

/** Bins any supported observation taken from `robotPose` into `grid` bins:
 * what toSensorFrame() adapts, and CObservation2DRangeScan. Heights are in the
 * grid (map) frame. Returns false if the class is not supported; throws
 * std::invalid_argument (with a message naming the field) for malformed
 * observations. */
bool binObservation(
	const mrpt::obs::CObservation& obs, const mrpt::poses::CPose3D& robotPose, const ProjectionFilter& filter,
	const ElevationGrid& grid, DepthProjector& projector, BinnedPoints& out, size_t* pointsBinned = nullptr);

/** Bins a point cloud given in the frame `pose` (points are first mapped by it). */
size_t binPointCloud(
	const mrpt::maps::CPointsMap& pts, const mrpt::poses::CPose3D& pose, const ProjectionFilter& f,
	const ElevationGrid& grid, BinnedPoints& out);

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

}  // namespace gam::maps
