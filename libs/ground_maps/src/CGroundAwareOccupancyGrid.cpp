#include <mrpt/config/CConfigFileBase.h>
#include <mrpt/maps/CGroundAwareOccupancyGrid.h>
#include <mrpt/maps/gam_observation_adapters.h>
#include <mrpt/obs/CObservation2DRangeScan.h>
#include <mrpt/obs/CObservation3DRangeScan.h>
#include <mrpt/obs/CObservationPointCloud.h>
#include <mrpt/serialization/CArchive.h>

#include <chrono>
#include <cmath>
#include <sstream>
#include <stdexcept>

using namespace mrpt::maps;

MAP_DEFINITION_REGISTER(
	"mrpt::maps::CGroundAwareOccupancyGrid,groundAwareGrid", mrpt::maps::CGroundAwareOccupancyGrid)
IMPLEMENTS_SERIALIZABLE(CGroundAwareOccupancyGrid, COccupancyGridMap2D, mrpt::maps)

CGroundAwareOccupancyGrid::TMapDefinition::TMapDefinition()
{
	// As the constructor: a Leddar "no return" is not free space (an .ini
	// key in _insertOpts still overrides it).
	insertionOpts.considerInvalidRangesAsFreeSpace = false;
}

void CGroundAwareOccupancyGrid::TMapDefinition::loadFromConfigFile_map_specific(
	const mrpt::config::CConfigFileBase& source, const std::string& sectionNamePrefix)
{
	const std::string sC = sectionNamePrefix + "_creationOpts";
	gam::ini::loadGridExtent(source, sC, min_x, max_x, min_y, max_y, resolution);
	insertionOpts.loadFromConfigFile(source, sectionNamePrefix + "_insertOpts");
	likelihoodOpts.loadFromConfigFile(source, sectionNamePrefix + "_likelihoodOpts");
	groundOpts.loadFromConfigFile(source, sectionNamePrefix + "_groundOpts");
}

void CGroundAwareOccupancyGrid::TMapDefinition::dumpToTextStream_map_specific(std::ostream& out) const
{
	out << "min_x=" << min_x << " max_x=" << max_x << " min_y=" << min_y << " max_y=" << max_y
		<< " resolution=" << resolution << "\n";
	insertionOpts.dumpToTextStream(out);
	likelihoodOpts.dumpToTextStream(out);
	groundOpts.dumpToTextStream(out);
}

mrpt::maps::CMetricMap* CGroundAwareOccupancyGrid::internal_CreateFromMapDefinition(
	const TMetricMapInitializer& _def)
{
	const auto& def = dynamic_cast<const CGroundAwareOccupancyGrid::TMapDefinition&>(_def);
	auto* m = new CGroundAwareOccupancyGrid(def.min_x, def.max_x, def.min_y, def.max_y, def.resolution);
	m->insertionOptions = def.insertionOpts;
	m->likelihoodOptions = def.likelihoodOpts;
	m->groundOptions = def.groundOpts;
	return m;
}

// ---------------------------------------------------------------------------
gam::ini::Fields CGroundAwareOccupancyGrid::TGroundAwareOptions::fields()
{
	return {
		// 2.5D map
		{"m_x", &m_x, 3, 20000, "cells of the robot-centred 2.5D map along x"},
		{"m_y", &m_y, 3, 20000, "cells of the robot-centred 2.5D map along y"},
		{"z_min", &z_min, -100, 100, "lowest robot-frame z kept [m] (floor = 0; keep it low to see drops)"},
		{"z_max", &z_max, -100, 100, "highest robot-frame z kept [m]"},
		{"min_range", &min_range, 0, 1000, "closer sensor returns are dropped [m]"},
		{"max_range", &max_range, 0.01, 1000, "farther sensor returns are dropped [m]"},
		{"decimation", &decimation, 1, 64, "use every n-th pixel row/column"},
		{"outlier_filter", &outlier_filter, 0, 1, "3-sigma rule per cell"},
		{"outlier_sigmas", &outlier_sigmas, 0.5, 100, "k of the k-sigma rule"},
		{"outlier_min_count", &outlier_min_count, 2, 1000000, "cells with fewer samples are not filtered"},
		{"idw_radius", &idw_radius, 0, 20, "IDW radius for the local fits [cells], 0 = off"},
		// RRT-GPD (Table I)
		{"K", &K, 1, 1000000, "RRT-GPD iterations"},
		{"N_th", &N_th, 1e-6, 1, "max horizontal part of a node's unit normal (sin of tilt)"},
		{"E_th", &E_th, 1e-6, 10, "max height step from the parent's local plane [m]"},
		{"s_x", &s_x, 3, 31, "local fit neighbourhood along x [cells, odd]"},
		{"s_y", &s_y, 3, 31, "local fit neighbourhood along y [cells, odd]"},
		{"d_n", &d_n, 1e-3, 100, "node expansion distance [m]"},
		{"max_cell_std", &max_cell_std, 1e-6, 10, "cells rougher than this are not surfaces [m]"},
		{"max_fit_rms", &max_fit_rms, 1e-6, 10, "local fits with a larger RMS are not planar [m]"},
		{"min_valid_cells", &min_valid_cells, 3, 961, "cells with a height a local fit needs"},
		{"seed_search_radius", &seed_search_radius, 1e-3, 1000, "seed within this distance of the robot [m]"},
		{"seed_height_tolerance", &seed_height_tolerance, 1e-3, 100, "seed height vs robot floor [m]"},
		{"seed_attempts", &seed_attempts, 1, 100, "seeds tried when a tree stays too small"},
		{"window_margin", &window_margin, 1e-3, 1000, "sampling window margin around the nodes [m]"},
		{"min_nodes", &min_nodes, 3, 1000000, "fewer tree nodes = no ground"},
		{"ransac_iterations", &ransac_iterations, 1, 1000000, "RANSAC iterations on the nodes"},
		{"ransac_inlier_distance", &ransac_inlier_distance, 1e-6, 10, "RANSAC inlier distance [m]"},
		{"min_nodes_per_extra_plane", &min_nodes_per_extra_plane, 0, 1000000, "nodes an extra ground patch (ramp) needs; 0 = none"},
		{"max_planes", &max_planes, 1, 8, "ground plane + extra patches"},
		{"random_seed", &random_seed, 0, 2147483647, "RNG seed (same seed, same result)"},
		// ISM (Table I)
		{"d_pth", &d_pth, 1e-6, 10, "plane distance threshold [m]"},
		{"K_g", &K_g, 0, 0.499, "ground gain"},
		{"sigma2", &sigma2, 1e-9, 100, "variance of the ground Gaussian [m^2]"},
		{"K_n", &K_n, 1e-12, 1e6, "density gain [m^3/point]"},
		{"d_min", &d_min, -1e6, 1e6, "density sigmoid offset"},
		{"K_m", &K_m, 0, 0.999, "obstacle gain"},
		{"depth_noise_c0", &depth_noise_c0, 0, 1, "sensor depth noise sigma = c0 + c2 r^2: c0 [m]"},
		{"depth_noise_c2", &depth_noise_c2, 0, 1, "c2 [1/m]"},
		{"noise_sigmas", &noise_sigmas, 0, 10, "ground band = d_pth + noise_sigmas * vertical noise; 0 = fixed d_pth"},
		{"min_obstacle_points", &min_obstacle_points, 1, 1000000, "obstacle/drop voxels with fewer samples are ignored (depth spikes)"},
		{"measure_floor_noise", &measure_floor_noise, 0, 1, "band from the floor's scatter measured in each frame (model where too little floor)"},
		{"floor_noise_min_cells", &floor_noise_min_cells, 1, 1000000, "floor cells a 0.5 m range bin needs to be measured"},
		{"robot_height", &robot_height, 1e-3, 100, "voxels entirely above this do not block [m]"},
		{"drop_rays", &drop_rays, 0, 1, "mark cells where rays went below the ground"},
		{"max_drop_ray_length", &max_drop_ray_length, 0, 100, "longest drop ray [m]"},
		{"drop_ray_min_points", &drop_ray_min_points, 1, 1000000, "samples a drop voxel needs to cast its ray"},
		{"local_planes", &local_planes, 0, 1, "use ramp patches near their nodes"},
		{"plane_support_radius", &plane_support_radius, 0, 100, "reach of a ramp patch around its nodes [m]"},
		// 2D scans
		{"sparse_scan_upsampling", &sparse_scan_upsampling, 1, 1000, "rays per beam for scans with < 64 beams"},
		{"scan_keeps_3d_obstacles", &scan_keeps_3d_obstacles, 0, 1, "2D scans free only cells already free (seen floor)"}};
}

void CGroundAwareOccupancyGrid::TGroundAwareOptions::loadFromConfigFile(
	const mrpt::config::CConfigFileBase& source, const std::string& section)
{
	gam::ini::loadThenCheck(fields(), source, section, [this] { validate(); });
}

void CGroundAwareOccupancyGrid::TGroundAwareOptions::saveToConfigFile(
	mrpt::config::CConfigFileBase& target, const std::string& section) const
{
	gam::ini::save(const_cast<TGroundAwareOptions*>(this)->fields(), target, section);
}

void CGroundAwareOccupancyGrid::TGroundAwareOptions::validate() const
{
	gam::ini::validate(const_cast<TGroundAwareOptions*>(this)->fields(), "groundOpts");
	if (!(z_min < z_max)) throw std::invalid_argument("groundOpts: z_min must be < z_max");
	if (!(min_range < max_range)) throw std::invalid_argument("groundOpts: min_range must be < max_range");
	{
		// The per-frame 2.5D map: refuse what would not fit in memory before allocating it.
		gam::GridGeometry g;
		g.nx = m_x;
		g.ny = m_y;
		try
		{
			g.validate();
		}
		catch (const std::invalid_argument& e)
		{
			throw std::invalid_argument(std::string("groundOpts: m_x x m_y: ") + e.what());
		}
	}
	rrtParams().validate();
	ismParams().validate();
}

gam::RrtGpdParams CGroundAwareOccupancyGrid::TGroundAwareOptions::rrtParams() const
{
	gam::RrtGpdParams p;
	p.iterations = K;
	p.normal_threshold = N_th;
	p.elevation_threshold = E_th;
	p.neighbourhood_x = s_x;
	p.neighbourhood_y = s_y;
	p.expansion_distance = d_n;
	p.max_cell_std = max_cell_std;
	p.max_fit_rms = max_fit_rms;
	p.min_valid_cells = min_valid_cells;
	p.seed_search_radius = seed_search_radius;
	p.seed_height_tolerance = seed_height_tolerance;
	p.window_margin = window_margin;
	p.seed_attempts = seed_attempts;
	p.min_nodes = size_t(min_nodes);
	p.ransac_iterations = ransac_iterations;
	p.ransac_inlier_distance = ransac_inlier_distance;
	p.min_nodes_per_extra_plane = size_t(min_nodes_per_extra_plane);
	p.max_planes = max_planes;
	p.random_seed = uint32_t(random_seed);
	return p;
}

gam::IsmParams CGroundAwareOccupancyGrid::TGroundAwareOptions::ismParams() const
{
	gam::IsmParams p;
	p.d_pth = d_pth;
	p.K_g = K_g;
	p.sigma2 = sigma2;
	p.K_n = K_n;
	p.d_min = d_min;
	p.K_m = K_m;
	p.depth_noise_c0 = depth_noise_c0;
	p.depth_noise_c2 = depth_noise_c2;
	p.noise_sigmas = noise_sigmas;
	p.measure_floor_noise = measure_floor_noise;
	p.floor_noise_min_cells = floor_noise_min_cells;
	p.min_obstacle_points = min_obstacle_points;
	p.robot_height = robot_height;
	p.max_range = max_range;
	p.drop_rays = drop_rays;
	p.max_drop_ray_length = max_drop_ray_length;
	p.drop_ray_min_points = drop_ray_min_points;
	p.local_planes = local_planes;
	p.plane_support_radius = plane_support_radius;
	return p;
}

gam::ProjectionFilter CGroundAwareOccupancyGrid::TGroundAwareOptions::projectionFilter(double robotZ) const
{
	gam::ProjectionFilter f;
	f.min_range = min_range;
	f.max_range = max_range;
	f.z_min = float(robotZ + z_min);
	// Points above the robot can never block it; dropping them here keeps a
	// beam or a door frame from merging with the floor below it into one tall
	// 2.5D column (a cell keeps only z-min and z-max).
	f.z_max = float(robotZ + std::min<double>(z_max, robot_height));
	f.decimation = decimation;
	return f;
}

gam::OutlierFilterParams CGroundAwareOccupancyGrid::TGroundAwareOptions::outlierParams() const
{
	gam::OutlierFilterParams p;
	p.enabled = outlier_filter;
	p.sigmas = outlier_sigmas;
	p.min_count = uint32_t(outlier_min_count);
	return p;
}

// ---------------------------------------------------------------------------
CGroundAwareOccupancyGrid::CGroundAwareOccupancyGrid(
	float min_x, float max_x, float min_y, float max_y, float resolution)
	: COccupancyGridMap2D(min_x, max_x, min_y, max_y, resolution)
{
	// Converted depth scans and Leddar segments report "no return" often;
	// that is not evidence of free space.
	insertionOptions.considerInvalidRangesAsFreeSpace = false;
}

std::string CGroundAwareOccupancyGrid::asString() const
{
	std::ostringstream s;
	s << "CGroundAwareOccupancyGrid " << getSizeX() << "x" << getSizeY() << " cells at "
	  << getResolution() << " m, x[" << getXMin() << "," << getXMax() << "] y[" << getYMin() << ","
	  << getYMax() << "]";
	return s.str();
}

mrpt::obs::CObservation2DRangeScan CGroundAwareOccupancyGrid::upsampleSparseScan(
	const mrpt::obs::CObservation2DRangeScan& in, int k)
{
	const size_t N = in.getScanSize();
	if (k <= 1 || N == 0 || N >= 64) return in;
	mrpt::obs::CObservation2DRangeScan out = in;
	out.resizeScan(N * size_t(k));
	for (size_t i = 0; i < N; i++)
		for (int j = 0; j < k; j++)
		{
			const size_t o = i * size_t(k) + size_t(j);
			out.setScanRange(o, in.getScanRange(i));
			out.setScanRangeValidity(o, in.getScanRangeValidity(i));
		}
	return out;
}

bool CGroundAwareOccupancyGrid::internal_insertObservation(
	const mrpt::obs::CObservation& obs, const std::optional<const mrpt::poses::CPose3D>& robotPose)
{
	using namespace mrpt::obs;
	const mrpt::poses::CPose3D pose = robotPose ? *robotPose : mrpt::poses::CPose3D();
	if (const auto* o2 = dynamic_cast<const CObservation2DRangeScan*>(&obs))
		return insert2D(*o2, robotPose);
	if (IS_CLASS(obs, CObservation3DRangeScan) || IS_CLASS(obs, CObservationPointCloud))
		return insert3D(obs, pose);
	return COccupancyGridMap2D::internal_insertObservation(obs, robotPose);
}

bool CGroundAwareOccupancyGrid::insert2D(
	const mrpt::obs::CObservation2DRangeScan& rawScan, const std::optional<const mrpt::poses::CPose3D>& robotPose)
{
	const auto scan = gam::mrpt_glue::safeScanFor(*this, rawScan, robotPose ? *robotPose : mrpt::poses::CPose3D());
	const bool sparse = int(scan.getScanSize()) < 64 && groundOptions.sparse_scan_upsampling > 1;
	const auto up = sparse ? upsampleSparseScan(scan, groundOptions.sparse_scan_upsampling)
						   : mrpt::obs::CObservation2DRangeScan();
	const auto& use = sparse ? up : scan;
	if (!groundOptions.scan_keeps_3d_obstacles)
		return COccupancyGridMap2D::internal_insertObservation(use, robotPose);

	// A planar beam sees only its own height: passing over a hole, a cable or
	// a 5 cm box says nothing about the floor. So the beam model adds its hits
	// and may reinforce cells already known free, but may not make an unknown
	// or occupied cell any freer: only seen floor is free.
	const std::vector<cellType> before = m_map;
	const float x0 = getXMin(), y0 = getYMin();
	const int sx0 = int(getSizeX()), sy0 = int(getSizeY());
	const bool changed = COccupancyGridMap2D::internal_insertObservation(use, robotPose);
	const int sx = int(getSizeX()), sy = int(getSizeY());
	// The grid may have grown (cell alignment is kept): shift the old indices.
	const int ox = int(std::lround((x0 - getXMin()) / getResolution()));
	const int oy = int(std::lround((y0 - getYMin()) / getResolution()));
	for (int cy = 0; cy < sy0; cy++)
		for (int cx = 0; cx < sx0; cx++)
		{
			const cellType old = before[size_t(cy) * size_t(sx0) + size_t(cx)];
			if (old > 0) continue;	// free before: any update is fine
			const int nx = cx + ox, ny = cy + oy;
			if (nx < 0 || ny < 0 || nx >= sx || ny >= sy) continue;
			cellType& now = m_map[size_t(ny) * size_t(sx) + size_t(nx)];
			if (now > old) now = old;
		}
	return changed;
}

bool CGroundAwareOccupancyGrid::insert3D(
	const mrpt::obs::CObservation& obs, const mrpt::poses::CPose3D& robotPose)
{
	using clk = std::chrono::steady_clock;
	auto ms = [](clk::time_point a, clk::time_point b) {
		return std::chrono::duration<double, std::milli>(b - a).count();
	};
	const auto t0 = clk::now();
	const auto& o = groundOptions;
	if (!std::isfinite(robotPose.x()) || !std::isfinite(robotPose.y()) || !std::isfinite(robotPose.z()))
		throw std::invalid_argument("robot pose is not finite");
	resetLastFrame();

	// 1. The robot-centred 2.5D map, aligned with this grid's cells.
	const double res = getResolution();
	gam::GridGeometry g;
	g.resolution = res;
	g.nx = o.m_x;
	g.ny = o.m_y;
	g.x_min = getXMin() + std::round((robotPose.x() - 0.5 * o.m_x * res - getXMin()) / res) * res;
	g.y_min = getYMin() + std::round((robotPose.y() - 0.5 * o.m_y * res - getYMin()) / res) * res;
	const auto& cur = m_frame.geometry();
	if (cur.nx != g.nx || cur.ny != g.ny || cur.resolution != g.resolution)
		m_frame.resize(g);
	else
		m_frame.recenter(g.x_min, g.y_min);

	gam::mrpt_glue::BinningOptions bo;
	bo.filter = o.projectionFilter(robotPose.z());
	m_bins.clear();
	gam::mrpt_glue::binObservation(obs, robotPose, bo, m_frame, m_projector, m_bins);
	const auto t1 = clk::now();
	m_last.points = m_frame.insert(m_bins, o.outlierParams());
	if (o.idw_radius > 0)
	{
		gam::IdwParams idw;
		idw.radius_cells = o.idw_radius;
		m_frame.interpolateIdw(idw);
	}
	const auto t2 = clk::now();

	// 2. Ground.
	m_rrt.setParams(o.rrtParams());
	gam::GroundSeedHint hint;
	hint.x = robotPose.x();
	hint.y = robotPose.y();
	hint.floor_z = robotPose.z();
	m_rrt.detect(m_frame, hint, m_last.detection);
	const auto t3 = clk::now();

	// 3. Evidence.
	mrpt::poses::CPose3D sensorPose;
	if (const auto* o3 = dynamic_cast<const mrpt::obs::CObservation3DRangeScan*>(&obs))
		sensorPose = o3->sensorPose;
	else if (const auto* pc = dynamic_cast<const mrpt::obs::CObservationPointCloud*>(&obs))
		sensorPose = pc->sensorPose;
	const mrpt::poses::CPose3D sensorInMap = robotPose + sensorPose;
	m_last.sensor = Eigen::Vector3d(sensorInMap.x(), sensorInMap.y(), sensorInMap.z());
	m_ism.setParams(o.ismParams());
	m_ism.compute(m_frame, m_last.detection, m_last.sensor, m_last.ism);
	const auto t4 = clk::now();
	applyEvidence();
	const auto t5 = clk::now();

	m_last.valid = true;
	m_last.ms_projection = ms(t0, t1);
	m_last.ms_outliers = ms(t1, t2);
	m_last.ms_ground = ms(t2, t3);
	m_last.ms_ism = ms(t3, t4);
	m_last.ms_update = ms(t4, t5);
	m_last.ms_total = ms(t0, t5);
	// A frame is "inserted" even if it found no ground: it was processed, and
	// lastFrame() says why nothing changed.
	return true;
}

void CGroundAwareOccupancyGrid::resetLastFrame()
{
	// As m_last = TFrameDiagnostics{}, but the detection's vectors keep their
	// capacity: no heap allocation per frame once they have grown (issue #6).
	gam::GroundDetection detection = std::move(m_last.detection);
	m_last = TFrameDiagnostics{};
	detection.clear();
	m_last.detection = std::move(detection);
}

void CGroundAwareOccupancyGrid::applyEvidence()
{
	const auto& cells = m_ism.evidenceCells();
	if (cells.empty()) return;
	const auto& ev = m_ism.evidence();
	const auto& g = m_frame.geometry();

	// Grow the grid to hold the evidence (MRPT keeps the cell alignment).
	int x0 = g.nx, x1 = -1, y0 = g.ny, y1 = -1;
	for (uint32_t c : cells)
	{
		const int cx = int(c % uint32_t(g.nx)), cy = int(c / uint32_t(g.nx));
		x0 = std::min(x0, cx);
		x1 = std::max(x1, cx);
		y0 = std::min(y0, cy);
		y1 = std::max(y1, cy);
	}
	const float bx0 = float(g.x_min + x0 * g.resolution), bx1 = float(g.x_min + (x1 + 1) * g.resolution);
	const float by0 = float(g.y_min + y0 * g.resolution), by1 = float(g.y_min + (y1 + 1) * g.resolution);
	if (bx0 < getXMin() || bx1 > getXMax() || by0 < getYMin() || by1 > getYMax())
	{
		// A robot pose far from everything seen so far (corrupt odometry) would
		// otherwise grow the grid to terabytes.
		gam::mrpt_glue::checkGridSize(
			"growing the ground-aware grid to the robot pose", std::min(bx0, getXMin()), std::max(bx1, getXMax()),
			std::min(by0, getYMin()), std::max(by1, getYMax()), getResolution());
	}
	if (bx0 < getXMin() || bx1 > getXMax() || by0 < getYMin() || by1 > getYMax())
		resizeGrid(
			std::min(bx0, getXMin()), std::max(bx1, getXMax()), std::min(by0, getYMin()),
			std::max(by1, getYMax()), 0.5f, true);

	// Log-odds fusion: each cell gets one update per frame. MRPT cells hold
	// the log-odds of being FREE, so occupied evidence lowers them.
	const int sx = int(getSizeX()), sy = int(getSizeY());
	for (uint32_t c : cells)
	{
		const int cx = int(c % uint32_t(g.nx)), cy = int(c / uint32_t(g.nx));
		const int wx = x2idx(g.cx(cx)), wy = y2idx(g.cy(cy));
		if (wx < 0 || wy < 0 || wx >= sx || wy >= sy) continue;
		const float pFree = std::clamp(1.0f - ev[c], 0.001f, 0.999f);
		const int l = int(p2l(pFree));
		cellType& cell = m_map[size_t(wx) + size_t(wy) * getSizeX()];
		cell = cellType(std::clamp(int(cell) + l, int(OCCGRID_CELLTYPE_MIN), int(OCCGRID_CELLTYPE_MAX)));
	}
	m_is_empty = false;
	m_likelihoodCacheOutDated = true;
}

// ---------------------------------------------------------------------------
// Serialization: v0 = base grid (with its own version) + groundOptions as
// (key, value) pairs, so options added later read back old files.
uint8_t CGroundAwareOccupancyGrid::serializeGetVersion() const { return 0; }

void CGroundAwareOccupancyGrid::serializeTo(mrpt::serialization::CArchive& out) const
{
	out << COccupancyGridMap2D::serializeGetVersion();
	COccupancyGridMap2D::serializeTo(out);
	gam::ini::writeFields(const_cast<TGroundAwareOptions&>(groundOptions).fields(), out);
}

void CGroundAwareOccupancyGrid::serializeFrom(mrpt::serialization::CArchive& in, uint8_t version)
{
	switch (version)
	{
		case 0:
		{
			uint8_t baseVer;
			in >> baseVer;
			COccupancyGridMap2D::serializeFrom(in, baseVer);
			gam::ini::readFields(groundOptions.fields(), in, "CGroundAwareOccupancyGrid");
		}
		break;
		default: MRPT_THROW_UNKNOWN_SERIALIZATION_VERSION(version);
	}
}
