#include <gam/common/Strings.h>
#include <gam/core/PlaneFit.h>
#include <gam/mapper/Errors.h>
#include <gam/mapper/Mapper.h>
#include <gam/mapper/RawlogFrames.h>
#include <gam/maps/GridIO.h>
#include <gam/maps/MapRegistry.h>
#include <mrpt/config/CConfigFileMemory.h>
#include <mrpt/core/bits_math.h>
#include <mrpt/maps/CGroundAwareOccupancyGrid.h>
#include <mrpt/obs/CObservation2DRangeScan.h>
#include <mrpt/obs/CObservation3DRangeScan.h>

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <sstream>

namespace fs = std::filesystem;
using namespace mrpt::maps;

namespace gam::mapper
{
namespace
{

std::string fmtMs(double v)
{
	std::ostringstream s;
	s << std::fixed << std::setprecision(3) << v;
	return s.str();
}
}  // namespace

// ---------------------------------------------------------------------------
double percentile(std::vector<double> v, double p)
{
	if (v.empty()) return 0;
	std::sort(v.begin(), v.end());
	const double pos = p * double(v.size() - 1);
	const size_t i = size_t(std::floor(pos));
	const double f = pos - double(i);
	return i + 1 < v.size() ? v[i] * (1 - f) + v[i + 1] * f : v.back();
}
double MapTiming::median() const { return percentile(ms3D.empty() ? totalMs : ms3D, 0.5); }
double MapTiming::p95() const { return percentile(ms3D.empty() ? totalMs : ms3D, 0.95); }

std::string RunSummary::text() const
{
	std::ostringstream s;
	s << "frames: " << frames << " (" << frames3D << " 3D scans, " << frames2D << " 2D scans";
	if (framesWithoutOdometry) s << ", " << framesWithoutOdometry << " without odometry: robot at the origin";
	s << ") in " << std::fixed << std::setprecision(2) << seconds << " s";
	if (snapshots) s << "; " << snapshots << " snapshots";
	s << "\n";
	size_t wl = 5, wc = 5;
	for (const auto& m : maps) wl = std::max(wl, m.label.size()), wc = std::max(wc, m.className.size());
	const bool both = frames3D > 0 && frames2D > 0;
	if (both) s << "median / p95 over the 3D frames; 2D-scan frames in the last two columns\n";
	s << std::left << std::setw(int(wl) + 2) << "map" << std::setw(int(wc) + 2) << "class" << std::right
	  << std::setw(12) << "median_ms" << std::setw(12) << "p95_ms";
	if (both) s << std::setw(12) << "2d_median" << std::setw(12) << "2d_p95";
	s << "\n";
	for (const auto& m : maps)
	{
		s << std::left << std::setw(int(wl) + 2) << m.label << std::setw(int(wc) + 2) << m.className << std::right
		  << std::setw(12) << fmtMs(m.median()) << std::setw(12) << fmtMs(m.p95());
		if (both)
			s << std::setw(12) << fmtMs(percentile(m.ms2D, 0.5)) << std::setw(12) << fmtMs(percentile(m.ms2D, 0.95));
		s << "\n";
	}
	for (const auto& m : maps)
		if (!m.setMs.empty())
			s << m.label << ": " << m.setMs.size()
			  << " sets of depth frames of several cameras at one pose (threads > 1), per set: median "
			  << fmtMs(percentile(m.setMs, 0.5)) << " ms, p95 " << fmtMs(percentile(m.setMs, 0.95)) << " ms\n";
	for (const auto& n : notes) s << n << "\n";
	return s.str();
}

void createMaps(const mrpt::config::CConfigFileBase& ini, const std::string& section, mrpt::maps::CMultiMetricMap& out)
{
	TSetOfMetricMapInitializers inits;
	std::vector<MapSpec> specs;
	loadMapDefinitions(ini, section, inits, specs);
	out.setListOfMaps(inits);
}

std::map<std::string, mrpt::poses::CPose3D> readSensorPoses(
	const mrpt::config::CConfigFileBase& ini, const std::string& configName)
{
	std::map<std::string, mrpt::poses::CPose3D> out;
	std::vector<std::string> keys;
	ini.getAllKeys("sensor_poses", keys);
	for (const std::string& label : keys)
	{
		const std::string v = gam::stripIniComment(ini.read_string("sensor_poses", label, "", false));
		double x, y, z, yaw, pitch, roll;
		char extra = 0;
		if (std::sscanf(v.c_str(), "%lf %lf %lf %lf %lf %lf %c", &x, &y, &z, &yaw, &pitch, &roll, &extra) != 6 ||
			!std::isfinite(x + y + z + yaw + pitch + roll))
			throw ConfigError(
				configName + ": [sensor_poses] " + label + "=" + v +
				": expected six numbers, x y z [m] yaw pitch roll [deg]");
		out[label] = mrpt::poses::CPose3D(x, y, z, yaw * M_PI / 180, pitch * M_PI / 180, roll * M_PI / 180);
	}
	return out;
}

// ---------------------------------------------------------------------------
Mapper::Mapper(const MapperOptions& opts) : m_opts(opts)
{
	if (m_opts.snapshotEvery > 1000000)
		throw ConfigError("--snapshot-every=" + std::to_string(m_opts.snapshotEvery) + " is out of range [0, 1000000]");
	if (m_opts.localCells < 10 || m_opts.localCells > 100000)
		throw ConfigError("--local-size-cells=" + std::to_string(m_opts.localCells) + " is out of range [10, 100000]");
	mrpt::config::CConfigFileMemory ini(m_opts.configText);
	TSetOfMetricMapInitializers inits;
	try
	{
		loadMapDefinitions(ini, m_opts.section, inits, m_specs, &m_warnings);
	}
	catch (const ConfigError& e)
	{
		throw ConfigError(m_opts.configName + ": " + e.what());
	}
	try
	{
		m_maps.setListOfMaps(inits);
	}
	catch (const std::exception& e)
	{
		throw ConfigError(m_opts.configName + ": cannot create the maps: " + conciseError(e.what()));
	}
	m_sensorPoses = readSensorPoses(ini, m_opts.configName);
	if (m_maps.maps.size() != m_specs.size())
		throw ConfigError("internal: CMultiMetricMap created a different number of maps than the .ini defines");
	for (size_t i = 0; i < m_specs.size(); i++)
		if (m_maps.maps[i]->GetRuntimeClass()->className != m_specs[i].className)
			throw ConfigError("internal: CMultiMetricMap map order differs from the .ini order");
	if (!m_opts.initialMap.empty()) loadInitialMap();
	for (const auto& m : m_maps.maps)
		if (const auto* g = dynamic_cast<const CGroundAwareOccupancyGrid*>(m.get());
			g && g->groundOptions().threads > 1)
			m_frameSets = true;
}

void Mapper::loadInitialMap()
{
	mrpt::maps::COccupancyGridMap2D stock;
	try
	{
		stock = gam::maps::readStockGrid(m_opts.initialMap);
	}
	catch (const std::exception& e)
	{
		throw ConfigError("--initial-map: " + conciseError(e.what()));
	}
	std::string into, notInto;
	for (size_t i = 0; i < m_specs.size(); i++)
	{
		const gam::maps::MapTraits* t = gam::maps::findMapTraits(*m_maps.maps[i]);
		std::string& list = t && t->startFromGrid ? into : notInto;
		list += (list.empty() ? "" : ", ") + m_specs[i].label;
		if (t && t->startFromGrid) t->startFromGrid(*m_maps.maps[i], stock);
	}
	if (into.empty())
		throw ConfigError(
			"--initial-map " + m_opts.initialMap + ": no map of the .ini can start from a 2D grid (" + notInto + ")");
	char b[160];
	std::snprintf(
		b, sizeof b, "%u x %u cells at %.3f m, x [%.2f, %.2f] y [%.2f, %.2f]", stock.getSizeX(), stock.getSizeY(),
		stock.getResolution(), stock.getXMin(), stock.getXMax(), stock.getYMin(), stock.getYMax());
	m_initialMapNote = "initial map " + m_opts.initialMap + " (" + b + ") loaded into: " + into;
	if (!notInto.empty()) m_initialMapNote += "; not into " + notInto + " (cannot start from a grid)";
}

namespace
{
struct TmpDir
{
	std::string path;
	bool keep = false;
	~TmpDir()
	{
		if (!path.empty() && !keep)
		{
			std::error_code ec;
			fs::remove_all(path, ec);
		}
	}
};

bool stderrIsTty() { return isatty(2) != 0; }
}  // namespace

// The state of a run between begin() and end().
struct Mapper::RunState
{
	std::chrono::steady_clock::time_point tStart;
	RunSummary s;
	TmpDir tmp;
	std::ofstream timing, planes, patches, snapIndex;
	std::string snapDir;
	// Each map's traits (gam/maps/MapRegistry.h); the first map that finds
	// ground planes writes ground_planes.csv.
	std::vector<const gam::maps::MapTraits*> traits;
	int planesFrom = -1;
};

Mapper::~Mapper() = default;

void Mapper::abort() { m_run.reset(); }

const RunSummary& Mapper::runSoFar() const
{
	static const RunSummary none;
	return m_run ? m_run->s : none;
}

void Mapper::begin()
{
	using clk = std::chrono::steady_clock;
	m_run = std::make_unique<RunState>();
	RunState& r = *m_run;
	r.tStart = clk::now();
	RunSummary& s = r.s;

	// Output directory: create it and a private temporary folder inside it,
	// so nothing in DIR looks like a finished map until the very end.
	std::error_code ec;
	fs::create_directories(m_opts.outDir, ec);
	if (!fs::is_directory(m_opts.outDir))
		throw RunError("cannot create output directory " + m_opts.outDir + (ec ? ": " + ec.message() : ""));
	r.tmp.path = (fs::path(m_opts.outDir) / (".ground-aware-mapper.tmp." + std::to_string(getpid()))).string();
	fs::remove_all(r.tmp.path, ec);
	if (!fs::create_directory(r.tmp.path, ec))
		throw RunError("output directory " + m_opts.outDir + " is not writable" + (ec ? ": " + ec.message() : ""));

	r.timing.open(r.tmp.path + "/timing.csv");
	r.planes.open(r.tmp.path + "/ground_planes.csv");
	r.patches.open(r.tmp.path + "/ground_patches.csv");
	if (!r.timing || !r.planes || !r.patches) throw RunError("cannot write to " + r.tmp.path);
	r.timing << "frame,map,stage,ms\n";
	r.planes << "frame,a,b,c,d,nodes,status,mount_z,mount_pitch_deg,mount_roll_deg,mount_alarm,sensor\n";
	r.planes << std::setprecision(9);
	r.patches << "frame,patch,a,b,c,d,nodes,slope_deg,source,sensor\n";
	r.patches << std::setprecision(9);
	r.timing << std::fixed << std::setprecision(4);
	// Snapshots (--snapshot-every N): written into the temporary folder too,
	// published with the rest.
	r.snapDir = r.tmp.path + "/snapshots";
	if (m_opts.snapshotEvery)
	{
		fs::create_directory(r.snapDir, ec);
		r.snapIndex.open(r.snapDir + "/index.csv");
		if (!r.snapIndex) throw RunError("cannot write to " + r.snapDir);
		r.snapIndex << "snapshot,frames,frame_index,rawlog_entry,robot_x,robot_y,robot_yaw_deg\n";
		r.snapIndex << std::fixed << std::setprecision(6);
	}

	s.maps.resize(m_specs.size());
	for (size_t i = 0; i < m_specs.size(); i++)
	{
		s.maps[i].label = m_specs[i].label;
		s.maps[i].className = m_specs[i].className;
	}
	r.traits.assign(m_specs.size(), nullptr);
	for (size_t i = 0; i < m_specs.size(); i++)
	{
		r.traits[i] = gam::maps::findMapTraits(*m_maps.maps[i]);
		if (r.planesFrom < 0 && r.traits[i] && r.traits[i]->lastGroundPlane) r.planesFrom = int(i);
	}
}

void Mapper::applySensorPose(Frame& fr) const
{
	if (m_sensorPoses.empty()) return;
	const auto sp = m_sensorPoses.find(fr.obs->sensorLabel);
	if (sp != m_sensorPoses.end()) fr.obs->setSensorPose(sp->second);
}

void Mapper::countFrame(const Frame& fr, bool is3D)
{
	RunSummary& s = m_run->s;
	s.frames++;
	(is3D ? s.frames3D : s.frames2D)++;
	if (!fr.hasOdometry) s.framesWithoutOdometry++;
}

void Mapper::recordFrame(size_t i, const Frame& fr, bool is3D, double ms)
{
	RunState& r = *m_run;
	RunSummary& s = r.s;
	auto& map = *m_maps.maps[i];
	s.maps[i].totalMs.push_back(ms);
	(is3D ? s.maps[i].ms3D : s.maps[i].ms2D).push_back(ms);
	const std::string& L = m_specs[i].label;
	r.timing << fr.index << "," << L << ",total," << ms << "\n";
	const gam::maps::MapTraits* t = r.traits[i];
	if (t && t->stageTimes)
		t->stageTimes(map, is3D, [&](const char* stage, double stageMs) {
			r.timing << fr.index << "," << L << "," << stage << "," << stageMs << "\n";
		});
	gam::maps::GroundPlaneRecord gp;
	if (int(i) == r.planesFrom && is3D && t->lastGroundPlane(map, gp))
	{
		r.planes << fr.index << ",";
		if (gp.found)
			r.planes << gp.a << "," << gp.b << "," << gp.c << "," << gp.d;
		else
			r.planes << ",,,";
		r.planes << "," << gp.nodes << "," << gp.status << ",";
		if (gp.mount_measured)
			r.planes << gp.mount_z << "," << gp.mount_pitch_deg << "," << gp.mount_roll_deg << ","
					 << (gp.mount_alarm ? 1 : 0);
		else
			r.planes << ",,,";
		// Several cameras: each frame's plane is its own camera's.
		r.planes << "," << fr.obs->sensorLabel << "\n";
		// The ramp patches that judged the frame beside the ground: its own,
		// then those its camera's earlier frames fitted (patch_memory).
		for (size_t k = 0; k < gp.patches.size(); k++)
		{
			const auto& p = gp.patches[k];
			const double slope = gam::Plane{p.a, p.b, p.c, p.d}.tiltAngle() * 180.0 / M_PI;
			r.patches << fr.index << "," << k + 1 << "," << p.a << "," << p.b << "," << p.c << "," << p.d << ","
					  << p.nodes << "," << slope << "," << (p.remembered ? "remembered" : "frame") << ","
					  << fr.obs->sensorLabel << "\n";
		}
	}
}

void Mapper::afterFrames(const Frame& last)
{
	RunState& r = *m_run;
	RunSummary& s = r.s;
	m_lastPose = last.robotPose;
	if (m_opts.snapshotEvery && s.frames % m_opts.snapshotEvery == 0)
	{
		char name[32];
		std::snprintf(name, sizeof(name), "%06zu", s.frames);
		try
		{
			writeSnapshot(r.snapDir + "/" + name);
		}
		catch (const std::exception& e)
		{
			throw RunError("writing snapshot " + std::string(name) + ": " + conciseError(e.what()));
		}
		r.snapIndex << name << "," << s.frames << "," << last.index << "," << last.entry << "," << last.robotPose.x()
					<< "," << last.robotPose.y() << "," << mrpt::RAD2DEG(last.robotPose.yaw()) << "\n";
		s.snapshots++;
	}
}

void Mapper::insert(Frame& fr)
{
	using clk = std::chrono::steady_clock;
	if (!m_run) throw std::logic_error("Mapper::insert() before begin()");
	RunState& r = *m_run;
	applySensorPose(fr);
	const bool is3D = IS_CLASS(*fr.obs, mrpt::obs::CObservation3DRangeScan);
	countFrame(fr, is3D);

	for (size_t i = 0; i < m_specs.size(); i++)
	{
		auto& map = *m_maps.maps[i];
		const auto t0 = clk::now();
		try
		{
			map.insertObservation(*fr.obs, fr.robotPose);
		}
		catch (const std::exception& e)
		{
			throw RunError(
				"frame " + std::to_string(fr.index) + " (rawlog entry " + std::to_string(fr.entry) + "), map " +
				m_specs[i].label + ": " + conciseError(e.what()));
		}
		recordFrame(i, fr, is3D, std::chrono::duration<double, std::milli>(clk::now() - t0).count());
	}

	if (m_opts.localMap)
		for (size_t i = 0; i < m_specs.size(); i++)
			if (r.traits[i] && r.traits[i]->keepWindow)
				r.traits[i]->keepWindow(*m_maps.maps[i], fr.robotPose.x(), fr.robotPose.y(), m_opts.localCells);
	afterFrames(fr);
}

void Mapper::insertSet(std::vector<Frame>& set)
{
	using clk = std::chrono::steady_clock;
	if (!m_run) throw std::logic_error("Mapper::insertSet() before begin()");
	if (set.size() == 1) return insert(set[0]);
	RunState& r = *m_run;
	RunSummary& s = r.s;
	for (Frame& fr : set)
	{
		applySensorPose(fr);
		countFrame(fr, true);
	}
	std::vector<const mrpt::obs::CObservation*> obs;
	for (const Frame& fr : set) obs.push_back(fr.obs.get());
	const mrpt::poses::CPose3D& pose = set[0].robotPose;
	for (size_t i = 0; i < m_specs.size(); i++)
	{
		auto& map = *m_maps.maps[i];
		const gam::maps::MapTraits* t = r.traits[i];
		const auto keepWindow = [&] {
			if (m_opts.localMap && t && t->keepWindow) t->keepWindow(map, pose.x(), pose.y(), m_opts.localCells);
		};
		size_t k = 0;  // the frame being inserted (for messages)
		try
		{
			if (auto* g = dynamic_cast<CGroundAwareOccupancyGrid*>(&map))
			{
				// The frames' pipelines run concurrently (threads); each frame
				// is then fused, recorded and windowed in order, as one by one.
				const auto t0 = clk::now();
				g->insertObservations(obs, pose, [&](size_t j) {
					k = j + 1;
					recordFrame(i, set[j], true, g->lastFrameTimes().total);
					keepWindow();
				});
				const double ms = std::chrono::duration<double, std::milli>(clk::now() - t0).count();
				s.maps[i].setMs.push_back(ms);
				r.timing << set[0].index << "," << m_specs[i].label << ",frame_set," << ms << "\n";
			}
			else
			{
				double setMs = 0;
				for (k = 0; k < set.size(); k++)
				{
					const auto t0 = clk::now();
					map.insertObservation(*set[k].obs, pose);
					const double ms = std::chrono::duration<double, std::milli>(clk::now() - t0).count();
					setMs += ms;
					recordFrame(i, set[k], true, ms);
					keepWindow();
				}
				s.maps[i].setMs.push_back(setMs);
				r.timing << set[0].index << "," << m_specs[i].label << ",frame_set," << setMs << "\n";
			}
		}
		catch (const RunError&)
		{
			throw;
		}
		catch (const std::exception& e)
		{
			const Frame& fr = set[std::min(k, set.size() - 1)];
			throw RunError(
				"frame " + std::to_string(fr.index) + " (rawlog entry " + std::to_string(fr.entry) + "), map " +
				m_specs[i].label + ": " + conciseError(e.what()));
		}
	}
	afterFrames(set.back());
}

bool Mapper::joinsSet(const std::vector<Frame>& set, const Frame& fr) const
{
	if (set.empty() || !IS_CLASS(*fr.obs, mrpt::obs::CObservation3DRangeScan)) return false;
	const Frame& first = set[0];
	if (!IS_CLASS(*first.obs, mrpt::obs::CObservation3DRangeScan)) return false;
	// Taken at one robot pose and one time, by another camera.
	const auto& a = first.robotPose;
	const auto& b = fr.robotPose;
	if (!(a.x() == b.x() && a.y() == b.y() && a.z() == b.z() && a.yaw() == b.yaw() && a.pitch() == b.pitch() &&
		  a.roll() == b.roll()) ||
		first.hasOdometry != fr.hasOdometry || first.obs->timestamp != fr.obs->timestamp)
		return false;
	for (const Frame& f : set)
		if (f.obs->sensorLabel == fr.obs->sensorLabel) return false;
	// A snapshot is of the maps after a given number of frames: a set ends there.
	const size_t n = m_opts.snapshotEvery;
	if (n && (m_run->s.frames + set.size()) % n == 0) return false;
	return true;
}

std::vector<std::string> Mapper::publishMapsNow()
{
	if (!m_run) throw std::logic_error("Mapper::publishMapsNow() before begin()");
	// Into a folder of its own inside the temporary one, then file by file
	// into DIR: rename() replaces a file at once, so a reader of DIR sees the
	// previous or the new file, never a part of one.
	const fs::path dir = fs::path(m_run->tmp.path) / "live_snapshot";
	std::error_code ec;
	fs::remove_all(dir, ec);
	std::vector<std::string> files;
	try
	{
		if (!fs::create_directory(dir, ec)) throw std::runtime_error("cannot create " + dir.string());
		writeMaps(dir.string(), files);
	}
	catch (const std::exception& e)
	{
		throw RunError("writing a snapshot of the maps: " + conciseError(e.what()));
	}
	for (const auto& f : files)
	{
		fs::rename(dir / f, fs::path(m_opts.outDir) / f, ec);
		if (ec) throw RunError("cannot move " + f + " into " + m_opts.outDir + ": " + ec.message());
	}
	fs::remove_all(dir, ec);
	return files;
}

RunSummary Mapper::end()
{
	if (!m_run) throw std::logic_error("Mapper::end() before begin()");
	RunState& r = *m_run;
	RunSummary& s = r.s;
	std::error_code ec;
	for (size_t i = 0; i < m_specs.size(); i++)
		if (r.traits[i] && r.traits[i]->runNote)
		{
			const std::string note = r.traits[i]->runNote(*m_maps.maps[i]);
			if (!note.empty()) s.notes.push_back(m_specs[i].label + ": " + note);
		}

	r.timing.close();
	r.planes.close();
	r.patches.close();
	if (!r.timing || !r.planes || !r.patches)
		throw RunError("cannot write timing.csv / ground_planes.csv / ground_patches.csv in " + r.tmp.path);
	if (m_opts.snapshotEvery)
	{
		r.snapIndex.close();
		if (!r.snapIndex) throw RunError("cannot write " + r.snapDir + "/index.csv");
	}

	// Maps.
	try
	{
		writeMaps(r.tmp.path, s.files);
		std::ofstream cfg(r.tmp.path + "/config_used.ini");
		cfg << m_opts.configText;
		if (!cfg) throw std::runtime_error("cannot write config_used.ini");
	}
	catch (const std::exception& e)
	{
		throw RunError("writing outputs: " + conciseError(e.what()));
	}
	s.files.push_back("timing.csv");
	s.files.push_back("ground_planes.csv");
	s.files.push_back("ground_patches.csv");
	s.files.push_back("config_used.ini");

	// Publish: move everything into DIR.
	for (const auto& f : s.files)
	{
		fs::rename(fs::path(r.tmp.path) / f, fs::path(m_opts.outDir) / f, ec);
		if (ec) throw RunError("cannot move " + f + " into " + m_opts.outDir + ": " + ec.message());
	}
	if (m_opts.snapshotEvery)
	{
		// The snapshots of an earlier run go only now, replaced as a whole.
		const fs::path dst = fs::path(m_opts.outDir) / "snapshots";
		fs::remove_all(dst, ec);
		fs::rename(r.snapDir, dst, ec);
		if (ec) throw RunError("cannot move snapshots into " + m_opts.outDir + ": " + ec.message());
	}
	s.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - r.tStart).count();
	RunSummary out = std::move(s);
	m_run.reset();  // removes the temporary folder
	return out;
}

RunSummary Mapper::run()
{
	using clk = std::chrono::steady_clock;

	// 1. Input (before touching DIR).
	std::unique_ptr<RawlogFrameReader> reader;
	try
	{
		reader = std::make_unique<RawlogFrameReader>(m_opts.rawlogPath);
	}
	catch (const std::exception& e)
	{
		throw RunError(e.what());
	}

	// 2. Output directory and the run's files.
	begin();
	const RunSummary& s = m_run->s;

	// 3. Frames.
	const bool tty = stderrIsTty();
	bool progressShown = false;
	auto clearProgress = [&] {
		if (progressShown && tty) std::cerr << "\r" << std::string(78, ' ') << "\r" << std::flush;
		progressShown = false;
	};
	const auto tStart = m_run->tStart;
	auto lastProgress = clk::now();
	// threads > 1: the depth frames of several cameras at one pose go in as a set.
	std::vector<Frame> set;
	Frame fr;
	bool haveNext = false, atEnd = false;
	const auto readNext = [&] {
		try
		{
			haveNext = reader->next(fr) && !(m_opts.maxFrames && fr.index >= m_opts.maxFrames);
		}
		catch (const std::exception& e)
		{
			throw RunError(e.what());
		}
	};
	try
	{
		while (!atEnd)
		{
			if (m_opts.stopRequested && *m_opts.stopRequested) throw RunError("interrupted");
			if (!haveNext) readNext();
			if (!haveNext) break;
			set.clear();
			set.push_back(fr);
			haveNext = false;
			while (m_frameSets)
			{
				readNext();
				if (!haveNext)
				{
					atEnd = true;
					break;
				}
				if (!joinsSet(set, fr)) break;
				set.push_back(fr);
				haveNext = false;
			}
			insertSet(set);

			if (m_opts.progress)
			{
				const auto now = clk::now();
				const double since = std::chrono::duration<double>(now - lastProgress).count();
				if (since >= (tty ? 0.5 : 5.0))
				{
					lastProgress = now;
					const double el = std::chrono::duration<double>(now - tStart).count();
					std::cerr << (tty ? "\r" : "") << "ground-aware-mapper: frame " << s.frames << ", rawlog entry "
							  << reader->entriesRead() << ", " << std::fixed << std::setprecision(1)
							  << (el > 0 ? double(s.frames) / el : 0.0) << " frames/s, " << el << " s"
							  << (tty ? "   " : "\n") << std::flush;
					progressShown = true;
				}
			}
		}
	}
	catch (...)
	{
		clearProgress();
		abort();
		throw;
	}
	clearProgress();
	if (s.frames == 0)
	{
		abort();
		throw RunError(
			"no usable observation in " + m_opts.rawlogPath + " (" + std::to_string(reader->entriesRead()) +
			" entries; need CObservation3DRangeScan or CObservation2DRangeScan with data)");
	}

	// 4. Maps, 5. publish.
	return end();
}

}  // namespace gam::mapper
