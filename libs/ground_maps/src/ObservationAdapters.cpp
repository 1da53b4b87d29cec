#include <gam/maps/ObservationAdapters.h>
#include <mrpt/obs/CObservationPointCloud.h>

#include <cmath>
#include <sstream>
#include <stdexcept>

namespace gam::maps
{
RigidTransform toRigid(const mrpt::poses::CPose3D& p)
{
	RigidTransform T;
	const auto R = p.getRotationMatrix();
	for (int i = 0; i < 3; i++)
		for (int j = 0; j < 3; j++) T.R(i, j) = float(R(i, j));
	T.t = Eigen::Vector3f(float(p.x()), float(p.y()), float(p.z()));
	return T;
}

PinholeIntrinsics intrinsicsOf(const mrpt::obs::CObservation3DRangeScan& o)
{
	PinholeIntrinsics K;
	K.width = int(o.cameraParams.ncols);
	K.height = int(o.cameraParams.nrows);
	K.fx = o.cameraParams.fx();
	K.fy = o.cameraParams.fy();
	K.cx = o.cameraParams.cx();
	K.cy = o.cameraParams.cy();
	// TCamera::dist = [k1 k2 p1 p2 k3 ...] (plumb_bob)
	K.k1 = o.cameraParams.k1();
	K.k2 = o.cameraParams.k2();
	K.p1 = o.cameraParams.p1();
	K.p2 = o.cameraParams.p2();
	K.k3 = o.cameraParams.k3();
	return K;
}

namespace
{
bool finitePose(const mrpt::poses::CPose3D& p)
{
	return std::isfinite(p.x()) && std::isfinite(p.y()) && std::isfinite(p.z()) && std::isfinite(p.yaw()) &&
		   std::isfinite(p.pitch()) && std::isfinite(p.roll());
}
}  // namespace

size_t binPointCloud(
	const mrpt::maps::CPointsMap& pts, const mrpt::poses::CPose3D& pose, const ProjectionFilter& f,
	const ElevationGrid& grid, BinnedPoints& out)
{
	if (!finitePose(pose)) throw std::invalid_argument("point cloud pose is not finite");
	const auto& xs = pts.getPointsBufferRef_x();
	const auto& ys = pts.getPointsBufferRef_y();
	const auto& zs = pts.getPointsBufferRef_z();
	return binPoints(xs.data(), ys.data(), zs.data(), pts.size(), toRigid(pose), f, grid, out);
}

void placeSensor(const mrpt::poses::CPose3D& sensorInMap, SensorFrame& out)
{
	out.sensor_to_map = toRigid(sensorInMap);
	out.sensor_position = Eigen::Vector3d(sensorInMap.x(), sensorInMap.y(), sensorInMap.z());
}

bool toSensorFrame(const mrpt::obs::CObservation& obs, const mrpt::poses::CPose3D& robotPose, SensorFrame& out)
{
	using namespace mrpt::obs;
	if (!finitePose(robotPose)) throw std::invalid_argument("robot pose is not finite");
	out = SensorFrame{};
	out.sensor_label = obs.sensorLabel;
	if (const auto* o3 = dynamic_cast<const CObservation3DRangeScan*>(&obs))
	{
		o3->load();  // externally stored images
		if (!finitePose(o3->sensorPose))
			throw std::invalid_argument("CObservation3DRangeScan.sensorPose is not finite");
		if (o3->maxRange > 0) out.max_range = o3->maxRange;
		placeSensor(robotPose + o3->sensorPose, out);
		if (o3->hasRangeImage && o3->rangeImage.rows() > 0)
		{
			out.has_image = true;
			// CMatrix_u16 is row-major (Eigen::RowMajor), so data() walks rows.
			out.image.data = o3->rangeImage.data();
			out.image.rows = int(o3->rangeImage.rows());
			out.image.cols = int(o3->rangeImage.cols());
			out.image.stride = size_t(o3->rangeImage.cols());
			out.image.units = o3->rangeUnits;
			out.image.is_depth = o3->range_is_depth;
			out.intrinsics = intrinsicsOf(*o3);
		}
		else if (o3->hasPoints3D)
		{
			const size_t np = o3->points3D_x.size();
			if (o3->points3D_y.size() != np || o3->points3D_z.size() != np)
				throw std::invalid_argument("CObservation3DRangeScan.points3D_x/y/z sizes differ");
			out.x = o3->points3D_x.data();
			out.y = o3->points3D_y.data();
			out.z = o3->points3D_z.data();
			out.point_count = np;
		}
		return true;
	}
	if (const auto* pc = dynamic_cast<const CObservationPointCloud*>(&obs))
	{
		pc->load();
		if (!pc->pointcloud) return true;  // nothing to bin
		if (!finitePose(pc->sensorPose)) throw std::invalid_argument("CObservationPointCloud.sensorPose is not finite");
		placeSensor(robotPose + pc->sensorPose, out);
		const auto& P = *pc->pointcloud;
		out.x = P.getPointsBufferRef_x().data();
		out.y = P.getPointsBufferRef_y().data();
		out.z = P.getPointsBufferRef_z().data();
		out.point_count = P.size();
		return true;
	}
	return false;
}

bool binObservation(
	const mrpt::obs::CObservation& obs, const mrpt::poses::CPose3D& robotPose, const ProjectionFilter& filter,
	const ElevationGrid& grid, DepthProjector& projector, BinnedPoints& out, size_t* pointsBinned)
{
	using namespace mrpt::obs;
	size_t n = 0;
	SensorFrame frame;
	if (toSensorFrame(obs, robotPose, frame))
		n = binSensorFrame(frame, filter, grid, projector, out);
	else if (const auto* o2 = dynamic_cast<const CObservation2DRangeScan*>(&obs))
	{
		if (!finitePose(o2->sensorPose))
			throw std::invalid_argument("CObservation2DRangeScan.sensorPose is not finite");
		ProjectionFilter f = filter;
		if (o2->maxRange > 0) f.max_range = std::min(f.max_range, o2->maxRange);
		// Sensor-frame points of the valid beams (range limits apply to them).
		const size_t N = o2->getScanSize();
		std::vector<float> xs, ys, zs;
		xs.reserve(N);
		ys.reserve(N);
		for (size_t i = 0; i < N; i++)
		{
			if (!o2->getScanRangeValidity(i)) continue;
			const float r = o2->getScanRange(i);
			if (!std::isfinite(r) || r <= 0) continue;
			const float a = o2->getScanAngle(i);
			xs.push_back(r * std::cos(a));
			ys.push_back(r * std::sin(a));
		}
		zs.assign(xs.size(), 0.f);
		n = binPoints(xs.data(), ys.data(), zs.data(), xs.size(), toRigid(robotPose + o2->sensorPose), f, grid, out);
	}
	else
		return false;
	if (pointsBinned) *pointsBinned = n;
	return true;
}

void checkRangeScan(const mrpt::obs::CObservation3DRangeScan& o)
{
	if (!finitePose(o.sensorPose)) throw std::invalid_argument("CObservation3DRangeScan.sensorPose is not finite");
	if (o.hasRangeImage && o.rangeImage.rows() > 0 && o.rangeImage.cols() > 0)
	{
		const PinholeIntrinsics K = intrinsicsOf(o);
		K.validate();
		if (int(o.rangeImage.rows()) != K.height || int(o.rangeImage.cols()) != K.width)
			throw std::invalid_argument(
				"range image is " + std::to_string(o.rangeImage.cols()) + "x" + std::to_string(o.rangeImage.rows()) +
				" but the camera parameters say " + std::to_string(K.width) + "x" + std::to_string(K.height));
		if (!(o.rangeUnits > 0) || !std::isfinite(o.rangeUnits))
			throw std::invalid_argument("rangeUnits must be > 0 (got " + std::to_string(o.rangeUnits) + ")");
	}
	if (o.hasPoints3D && (o.points3D_y.size() != o.points3D_x.size() || o.points3D_z.size() != o.points3D_x.size()))
		throw std::invalid_argument("CObservation3DRangeScan.points3D_x/y/z sizes differ");
}

void checkGridSize(const std::string& what, double x0, double x1, double y0, double y1, double resolution)
{
	if (!std::isfinite(x0) || !std::isfinite(x1) || !std::isfinite(y0) || !std::isfinite(y1) ||
		!std::isfinite(resolution) || !(resolution > 0))
		throw std::invalid_argument(what + ": grid extent or resolution is not finite");
	const double nx = std::ceil((x1 - x0) / resolution), ny = std::ceil((y1 - y0) / resolution);
	if (nx * ny > kMaxGridCells)
	{
		std::ostringstream s;
		s << what << ": a grid of " << nx << " x " << ny << " cells (x " << x0 << " to " << x1 << ", y " << y0 << " to "
		  << y1 << " at " << resolution << " m) is too large (limit " << kMaxGridCells
		  << " cells); shrink the area or use a coarser resolution";
		throw std::invalid_argument(s.str());
	}
}

void checkScanGrowth(
	const mrpt::maps::COccupancyGridMap2D& g, const mrpt::poses::CPose3D& sensorInMap, double farthestRange)
{
	if (!finitePose(sensorInMap)) throw std::invalid_argument("robot or sensor pose is not finite");
	const double reach = std::max({0.0, double(g.insertionOptions.maxDistanceInsertion), farthestRange}) + 1.0;
	const double x = sensorInMap.x(), y = sensorInMap.y();
	checkGridSize(
		"growing the grid to the scan", std::min<double>(g.getXMin(), x - reach),
		std::max<double>(g.getXMax(), x + reach), std::min<double>(g.getYMin(), y - reach),
		std::max<double>(g.getYMax(), y + reach), g.getResolution());
}

mrpt::obs::CObservation2DRangeScan safeScanFor(
	const mrpt::maps::COccupancyGridMap2D& g, const mrpt::obs::CObservation2DRangeScan& in,
	const mrpt::poses::CPose3D& robotPose)
{
	if (!std::isfinite(in.aperture) || !std::isfinite(in.maxRange))
		throw std::invalid_argument("CObservation2DRangeScan aperture or maxRange is not finite");
	mrpt::obs::CObservation2DRangeScan out = in;
	double farthest = 0;
	for (size_t i = 0; i < out.getScanSize(); i++)
	{
		if (!out.getScanRangeValidity(i)) continue;
		const float r = out.getScanRange(i);
		if (!std::isfinite(r) || !(r > 0) || (in.maxRange > 0 && r > in.maxRange))
			out.setScanRangeValidity(i, false);
		else
			farthest = std::max(farthest, double(r));
	}
	checkScanGrowth(g, robotPose + in.sensorPose, farthest);
	return out;
}

}  // namespace gam::maps
