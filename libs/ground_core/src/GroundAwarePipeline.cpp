#include "gam/core/GroundAwarePipeline.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>
#include <string>

namespace gam
{
void PipelineParams::validate() const
{
	checkParamRanges(*this, "");
	projection.validate();
	rrt.validate();
	missing.validate();
	{
		// The per-frame 2.5D map: refuse what would not fit in memory before allocating it.
		GridGeometry g;
		g.nx = m_x;
		g.ny = m_y;
		try
		{
			g.validate();
		}
		catch (const std::invalid_argument& e)
		{
			throw std::invalid_argument(std::string("m_x x m_y: ") + e.what());
		}
	}
}

ProjectionFilter PipelineParams::projectionFilter(double robotZ) const
{
	ProjectionFilter f = projection;
	f.z_min = float(robotZ + projection.z_min);
	// Points above the robot can never block it; dropping them here keeps a
	// beam or a door frame from merging with the floor below it into one tall
	// 2.5D column (a cell keeps only z-min and z-max).
	// (Not in the paper's model, which keeps everything the projection band holds.)
	const bool crop = ism.model != MethodVariant::Paper;
	f.z_max = float(robotZ + (crop ? std::min<double>(projection.z_max, ism.robot_height) : projection.z_max));
	// The paper projects every pixel.
	if (ism.model == MethodVariant::Paper) f.drop_flying_pixels = false;
	return f;
}

OutlierFilterParams PipelineParams::outlierFilter() const
{
	OutlierFilterParams f = outliers;
	if (ism.model == MethodVariant::Paper) f.min_band = 0.f;
	return f;
}

GroundAwarePipeline::GroundAwarePipeline(const PipelineParams& p)
{
	setParams(p);
	m_result.remembered_planes.reserve(PatchMemory::kMaxPlanes);
	m_result.remembered_support.reserve(PatchMemory::kMaxPlanes);
}

void GroundAwarePipeline::setParams(const PipelineParams& p)
{
	p.validate();
	m_rrt.setParams(p.rrt);
	m_ism.setParams(p.ism);
	m_missing.setParams(p.missing);
	m_params = p;
}

void GroundAwarePipeline::resetResult()
{
	// As m_result = FrameResult{}, but the detection's vectors keep their
	// capacity: no heap allocation per frame once they have grown.
	m_result.valid = false;
	m_result.samples = 0;
	m_result.points = 0;
	m_result.sensor.setZero();
	m_result.detection.clear();
	m_result.ism = IsmStats{};
	m_result.missing = MissingFloorStats{};
	m_result.camera = CameraModel::Custom;
	m_result.trust_range = std::numeric_limits<double>::infinity();
	m_result.remembered_planes.clear();
	m_result.remembered_support.clear();
	m_missing.clear();
	m_result.ms = StageTimes{};
}

void GroundAwarePipeline::forgetPatches() { m_patchMemory.clear(); }

void GroundAwarePipeline::rewindPatches() { m_patchMemory.restore(); }

Eigen::Vector2d GroundAwarePipeline::gridOrigin(const Eigen::Vector3d& robot, const GridLattice& lattice) const
{
	const double res = lattice.resolution;
	return {
		lattice.x0 + std::round((robot.x() - 0.5 * m_params.m_x * res - lattice.x0) / res) * res,
		lattice.y0 + std::round((robot.y() - 0.5 * m_params.m_y * res - lattice.y0) / res) * res};
}

void GroundAwarePipeline::placeGrid(const Eigen::Vector3d& robot, const GridLattice& lattice)
{
	// m_x x m_y cells centred on the robot, on the caller's cell lattice.
	const double res = lattice.resolution;
	GridGeometry g;
	g.resolution = res;
	g.nx = m_params.m_x;
	g.ny = m_params.m_y;
	const Eigen::Vector2d origin = gridOrigin(robot, lattice);
	g.x_min = origin.x();
	g.y_min = origin.y();
	const GridGeometry& cur = m_grid.geometry();
	if (cur.nx != g.nx || cur.ny != g.ny || cur.resolution != g.resolution)
		m_grid.resize(g);
	else
		m_grid.recenter(g.x_min, g.y_min);
}

const FrameResult& GroundAwarePipeline::process(
	const SensorFrame& frame, const Eigen::Vector3d& robot, const GridLattice& lattice)
{
	using clk = std::chrono::steady_clock;
	const auto ms = [](clk::time_point a, clk::time_point b) {
		return std::chrono::duration<double, std::milli>(b - a).count();
	};
	if (!robot.allFinite()) throw std::invalid_argument("robot pose is not finite");
	resetResult();
	const auto t0 = clk::now();

	// The camera (not in the paper's model): its noise model, and whether
	// its depth comes from disparity.
	const bool paperIsm = m_params.ism.model == MethodVariant::Paper;
	const CameraParams& cam = m_params.camera;
	if (!paperIsm)
		m_result.camera = cam.model != CameraModel::Auto ? cam.model
														 : detectCameraModel(
															   frame.sensor_label, frame.intrinsics.width,
															   frame.intrinsics.height, frame.intrinsics.fx);
	const CameraNoise noise = m_result.camera == CameraModel::Custom ? cam.custom : cameraNoisePreset(m_result.camera);

	// 1. The robot-centred 2.5D map of this frame.
	placeGrid(robot, lattice);
	m_bins.clear();
	ProjectionFilter filter = m_params.projectionFilter(robot.z());
	// Flying (mixed) pixels are a time-of-flight effect: a stereo or
	// structured-light pixel matches one surface or none. On such cameras the
	// filter only removes good edge pixels (D435 ablation: ramp false
	// obstacles 8.7 -> 6.6 %, nothing else changed, half the time).
	if (!paperIsm && noise.baseline > 0) filter.drop_flying_pixels = false;
	m_result.samples = binSensorFrame(frame, filter, m_grid, m_projector, m_bins);
	const auto t1 = clk::now();
	m_result.points = m_grid.insert(m_bins, m_params.outlierFilter());
	if (m_params.idw.radius_cells > 0)
	{
		m_grid.interpolateIdw(m_params.idw);
		if (m_params.idw_in_ism) m_grid.promoteIdwCells(m_params.idw.radius_cells);
	}
	const auto t2 = clk::now();

	// The range of trust of the camera: the map takes no evidence beyond it.
	double evidenceRange = m_params.projection.max_range;
	if (!paperIsm && cam.range_of_trust && frame.has_image)
	{
		m_result.trust_range = trustRange(
			noise, frame.intrinsics.fx, frame.sensor_position.z() - robot.z(), lattice.resolution,
			m_params.ism.noise_sigmas, m_params.ism.traversable_step, evidenceRange);
		evidenceRange = std::min(evidenceRange, m_result.trust_range);
	}

	// 2. Ground: RRT-GPD seeded under the robot.
	GroundSeedHint hint;
	hint.x = robot.x();
	hint.y = robot.y();
	hint.floor_z = robot.z();
	hint.sensor_x = frame.sensor_position.x();
	hint.sensor_y = frame.sensor_position.y();
	if (std::isfinite(m_result.trust_range)) hint.fill_range = evidenceRange;
	hint.judge_against_floor = m_params.max_ground_offset > 0;
	m_rrt.detect(m_grid, hint, m_result.detection);
	GroundDetection& det = m_result.detection;
	if (m_params.max_ground_offset > 0 && m_params.rrt.variant != MethodVariant::Paper && det.ok() &&
		std::abs(det.plane().heightAt(robot.x(), robot.y()) - robot.z()) > m_params.max_ground_offset)
	{
		// Not the floor the robot stands on: judge the frame against that floor.
		det.tree_plane = det.planes[0];
		det.planes[0] = hint.floorPlane();
		det.ground_from_mount = true;
	}
	// The ramp patches of this camera's earlier frames (in the map frame),
	// offered to the ISM beside this frame's planes (see PatchMemory).
	m_patchMemory.save();
	const double travelled = m_patchMemory.advance(robot.head<2>());
	const bool memory = !paperIsm && m_params.rrt.variant != MethodVariant::Paper && m_params.ism.local_planes;
	const GroundDetection& judged = m_patchMemory.apply(
		det, travelled, memory ? m_params.patch_memory : 0.0, det.patch_inlier_distance,
		m_params.ism.plane_support_radius, m_params.ism.traversable_step);
	m_result.remembered_planes.clear();
	m_result.remembered_support.clear();
	if (&judged != &det)
		for (size_t k = judged.remembered_from; k < judged.planes.size(); k++)
		{
			m_result.remembered_planes.push_back(judged.planes[k]);
			m_result.remembered_support.push_back(k < judged.plane_support.size() ? judged.plane_support[k] : 0);
		}
	const auto t3 = clk::now();

	// 3. Evidence, within the range of trust of the camera.
	m_result.sensor = frame.sensor_position;
	m_ism.setCameraNoise(noise, frame.intrinsics.fx);
	// The samples end where binSensorFrame cut them: a depth image on its
	// depth (the camera's x axis), a range image or a point cloud on the range.
	m_ism.setCameraRangeLimit(
		frame.has_image && frame.image.is_depth ? Eigen::Vector3d(frame.sensor_to_map.R.cast<double>().col(0))
												: Eigen::Vector3d::Zero(),
		sampleRangeLimit(frame, filter));
	m_ism.compute(m_grid, judged, m_result.sensor, evidenceRange, m_result.ism, &m_bins);
	const auto t4 = clk::now();

	// 4. Missing floor: where the ground predicts a floor return and the
	// camera returned nothing (an extension: not in the paper's model).
	if (m_params.missing.enabled && m_params.ism.model != MethodVariant::Paper && frame.has_image &&
		m_result.detection.ok() && m_result.ism.applied)
	{
		const double range = std::min<double>(frame.max_range, evidenceRange);
		m_missing.setSecondImagerBaseline(noise.baseline);
		m_missing.setRangeEndMargin(
			m_params.ism.noise_sigmas *
			std::hypot(noise.independent(range, frame.intrinsics.fx), noise.correlated(range, frame.intrinsics.fx)));
		m_missing.compute(
			frame, m_projector, m_params.projection.decimation, range, m_result.detection.plane(), m_grid,
			m_ism.classes(), m_result.missing, m_ism.patchSupport(m_grid.geometry().nx));
	}
	const auto t5 = clk::now();

	m_result.valid = true;
	m_result.ms.projection = ms(t0, t1);
	m_result.ms.outliers = ms(t1, t2);
	m_result.ms.ground = ms(t2, t3);
	m_result.ms.ism = ms(t3, t4);
	m_result.ms.missing = ms(t4, t5);
	return m_result;
}

}  // namespace gam
