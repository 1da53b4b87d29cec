// Ground-aware mapping for MRPT
// Glue between MRPT observations and the pure ground_core algorithms: turns
// observations into BinnedPoints of an ElevationGrid.
#pragma once

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

}  // namespace gam::mrpt_glue
