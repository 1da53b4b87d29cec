#include <gam/mapper/Errors.h>
#include <gam/mapper/GridIO.h>
#include <gam/mapper/Mapper.h>
#include <gam/mapper/RawlogFrames.h>
#include <mrpt/config/CConfigFileMemory.h>
#include <mrpt/io/CFileGZOutputStream.h>
#include <mrpt/maps/CElevation25DMap.h>
#include <mrpt/maps/CGroundAwareOccupancyGrid.h>
#include <mrpt/maps/CHeightBandOccupancyGrid.h>
#include <mrpt/maps/COctoMapGrid2D.h>
#include <mrpt/maps/TMetricMapTypesRegistry.h>
#include <mrpt/maps/registerGroundAwareMaps.h>
#include <mrpt/obs/CObservation2DRangeScan.h>
#include <mrpt/obs/CObservation3DRangeScan.h>
#include <mrpt/obs/CObservationPointCloud.h>
#include <mrpt/serialization/CArchive.h>

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <map>
#include <set>
#include <sstream>

namespace fs = std::filesystem;
using namespace mrpt::maps;

namespace gam::mapper
{
namespace
{
std::string firstLine(const std::string& s) { return conciseError(s); }

std::string trim(std::string s)
{
	while (!s.empty() && std::isspace((unsigned char)s.back())) s.pop_back();
	size_t i = 0;
	while (i < s.size() && std::isspace((unsigned char)s[i])) i++;
	return s.substr(i);
}

std::string stripComment(std::string raw)
{
	for (const char* c : {";", "//", "#"})
	{
		const auto pos = raw.find(c);
		if (pos != std::string::npos) raw = raw.substr(0, pos);
	}
	return trim(raw);
}

bool iequals(const std::string& a, const std::string& b)
{
	return a.size() == b.size() &&
		std::equal(a.begin(), a.end(), b.begin(), [](char x, char y) { return std::tolower(x) == std::tolower(y); });
}

/** Keys and sub-sections this project's classes accept. Empty = not ours. */
struct KnownSections
{
	bool ours = false;
	std::map<std::string, std::vector<std::string>> keysBySuffix;  ///< empty vector = any key
};

std::vector<std::string> fieldKeys(const gam::ini::Fields& f)
{
	std::vector<std::string> k;
	for (const auto& fl : f) k.push_back(fl.key);
	return k;
}

KnownSections knownSectionsOf(const std::string& className)
{
	KnownSections k;
	const std::vector<std::string> creation = {
		"min_x", "max_x", "min_y", "max_y", "resolution", "label", "enableSaveAs3DObject",
		"enableObservationLikelihood", "enableObservationInsertion"};
	if (className == "mrpt::maps::CGroundAwareOccupancyGrid")
	{
		CGroundAwareOccupancyGrid::TGroundAwareOptions o;
		k.ours = true;
		k.keysBySuffix = {{"_creationOpts", creation}, {"_insertOpts", {}}, {"_likelihoodOpts", {}},
						  {"_groundOpts", fieldKeys(o.fields())}};
	}
	else if (className == "mrpt::maps::CHeightBandOccupancyGrid")
	{
		CHeightBandOccupancyGrid::THeightBandOptions o;
		k.ours = true;
		k.keysBySuffix = {{"_creationOpts", creation}, {"_insertOpts", {}}, {"_likelihoodOpts", {}},
						  {"_bandOpts", fieldKeys(o.fields())}};
	}
	else if (className == "mrpt::maps::COctoMapGrid2D")
	{
		COctoMapGrid2D::TOctoOptions o;
		k.ours = true;
		k.keysBySuffix = {{"_creationOpts", creation}, {"_octoOpts", fieldKeys(o.fields())}};
	}
	else if (className == "mrpt::maps::CElevation25DMap")
	{
		CElevation25DMap::TInsertionOptions o;
		k.ours = true;
		k.keysBySuffix = {{"_creationOpts", creation}, {"_insertOpts", fieldKeys(o.fields())}};
	}
	return k;
}

bool validLabel(const std::string& l)
{
	if (l.empty() || l[0] == '.' || l.size() > 100) return false;
	return std::all_of(l.begin(), l.end(), [](char c) {
		return std::isalnum((unsigned char)c) || c == '_' || c == '-' || c == '.';
	});
}

std::string fmtMs(double v)
{
	std::ostringstream s;
	s << std::fixed << std::setprecision(3) << v;
	return s.str();
}
}  // namespace

namespace
{
std::string lower(std::string s)
{
	std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return char(std::tolower(c)); });
	return s;
}

/** Read-only view of a config that records every (section, key) read. */
class RecordingConfig : public mrpt::config::CConfigFileBase
{
   public:
	explicit RecordingConfig(const mrpt::config::CConfigFileBase& in) : m_in(in) {}
	void getAllSections(std::vector<std::string>& s) const override { m_in.getAllSections(s); }
	void getAllKeys(const std::string& sec, std::vector<std::string>& k) const override { m_in.getAllKeys(sec, k); }
	void clear() override {}
	bool wasRead(const std::string& sec, const std::string& key) const
	{
		return m_read.count(lower(sec) + "\n" + lower(key)) > 0;
	}

   protected:
	void writeString(const std::string&, const std::string&, const std::string&) override
	{
		throw std::logic_error("RecordingConfig is read-only");
	}
	std::string readString(
		const std::string& sec, const std::string& name, const std::string& def, bool failIfNotFound) const override
	{
		m_read.insert(lower(sec) + "\n" + lower(name));
		return m_in.read_string(sec, name, def, failIfNotFound);
	}

   private:
	const mrpt::config::CConfigFileBase& m_in;
	mutable std::set<std::string> m_read;
};
}  // namespace

// ---------------------------------------------------------------------------
void loadMapDefinitions(
	const mrpt::config::CConfigFileBase& iniIn, const std::string& section,
	TSetOfMetricMapInitializers& inits, std::vector<MapSpec>& specs, std::vector<std::string>* warnings)
{
	RecordingConfig ini(iniIn);
	mrpt::maps::registerGroundAwareMaps();
	inits.clear();
	specs.clear();
	if (!ini.sectionExists(section)) throw ConfigError("the configuration has no [" + section + "] section");

	const auto& reg = mrpt::maps::internal::TMetricMapTypesRegistry::Instance().getAllRegistered();

	// `<name>_count` keys naming no registered map are silently ignored by MRPT: reject them.
	std::vector<std::string> keys;
	ini.getAllKeys(section, keys);
	for (const auto& k : keys)
	{
		const std::string suffix = "_count";
		if (k.size() <= suffix.size() || k.compare(k.size() - suffix.size(), suffix.size(), suffix) != 0)
			continue;
		const std::string name = k.substr(0, k.size() - suffix.size());
		if (reg.find(name) == reg.end())
			throw ConfigError(
				"[" + section + "] " + k + ": unknown map type '" + name +
				"' (e.g. groundAwareGrid, heightBandGrid, octoMapGrid, CElevation25DMap, occupancyGrid, "
				"octoMap, pointsMap)");
	}

	std::set<std::string> labels;
	for (const auto& [name, ctors] : reg)
	{
		const std::string countKey = name + "_count";
		if (!ini.keyExists(section, countKey)) continue;
		const std::string raw = stripComment(ini.read_string(section, countKey, "0", false));
		char* end = nullptr;
		const long n = std::strtol(raw.c_str(), &end, 10);
		if (raw.empty() || *end != '\0' || n < 0 || n > 99)
			throw ConfigError("[" + section + "] " + countKey + "=" + raw + " is out of range [0, 99]");
		for (long i = 0; i < n; i++)
		{
			char nn[8];
			std::snprintf(nn, sizeof(nn), "%02u", unsigned(i));
			MapSpec sp;
			sp.iniName = name;
			sp.index = unsigned(i);
			sp.prefix = section + "_" + name + "_" + nn;
			TMetricMapInitializer::Ptr mi(TMetricMapInitializer::factory(name));
			if (!mi) throw ConfigError("cannot create map type '" + name + "'");
			sp.className = mi->getMetricMapClassType()->className;

			// Unknown keys and sub-sections of this project's map classes.
			const KnownSections known = knownSectionsOf(sp.className);
			if (known.ours)
			{
				std::vector<std::string> sections;
				ini.getAllSections(sections);
				for (const auto& sec : sections)
				{
					if (sec.size() <= sp.prefix.size() + 1 || sec.compare(0, sp.prefix.size() + 1, sp.prefix + "_") != 0)
						continue;
					const std::string suffix = sec.substr(sp.prefix.size());
					const auto it = std::find_if(
						known.keysBySuffix.begin(), known.keysBySuffix.end(),
						[&](const auto& kv) { return kv.first == suffix; });
					if (it == known.keysBySuffix.end())
					{
						std::string allowed;
						for (const auto& kv : known.keysBySuffix)
							allowed += (allowed.empty() ? "" : ", ") + sp.prefix + kv.first;
						throw ConfigError("unknown section [" + sec + "] (" + sp.className + " reads " + allowed + ")");
					}
					if (it->second.empty()) continue;
					std::vector<std::string> secKeys;
					ini.getAllKeys(sec, secKeys);
					for (const auto& k : secKeys)
						if (std::none_of(it->second.begin(), it->second.end(), [&](const std::string& a) {
								return iequals(a, k);
							}))
							throw ConfigError(
								"[" + sec + "] unknown key '" + k + "' (" + sp.className + " accepts: " + [&] {
									std::string s;
									for (const auto& a : it->second) s += (s.empty() ? "" : " ") + a;
									return s;
								}() + ")");
				}
			}

			try
			{
				mi->loadFromConfigFile(ini, sp.prefix);
			}
			catch (const std::exception& e)
			{
				throw ConfigError(firstLine(e.what()));
			}

			std::string defLabel = name + "_" + nn;
			std::replace(defLabel.begin(), defLabel.end(), ':', '_');
			sp.label = stripComment(ini.read_string(sp.prefix + "_creationOpts", "label", defLabel, false));

			// Keys the map's own loader never read: typos (errors for this project's
			// maps, warnings for stock MRPT maps, whose loaders may read keys conditionally).
			{
				std::vector<std::string> sections;
				ini.getAllSections(sections);
				for (const auto& sec : sections)
				{
					if (sec.size() <= sp.prefix.size() + 1 || lower(sec.substr(0, sp.prefix.size() + 1)) != lower(sp.prefix + "_"))
						continue;
					std::vector<std::string> secKeys;
					ini.getAllKeys(sec, secKeys);
					for (const auto& k : secKeys)
					{
						if (ini.wasRead(sec, k)) continue;
						const std::string msg = "[" + sec + "] key '" + k + "' is not used by " + sp.className;
						if (known.ours) throw ConfigError(msg);
						if (warnings) warnings->push_back(msg + " (typo?)");
					}
				}
			}
			if (sp.label.empty()) sp.label = defLabel;
			if (!validLabel(sp.label))
				throw ConfigError(
					"[" + sp.prefix + "_creationOpts] label=" + sp.label +
					" is not a valid file name stem (letters, digits, '_', '-', '.')");
			if (sp.label == "timing" || sp.label == "ground_planes" || sp.label == "config_used")
				throw ConfigError("[" + sp.prefix + "_creationOpts] label=" + sp.label + " is reserved");
			if (!labels.insert(sp.label).second)
				throw ConfigError("[" + sp.prefix + "_creationOpts] label=" + sp.label + " is used by two maps");
			inits.push_back(mi);
			specs.push_back(sp);
		}
	}
	if (specs.empty())
		throw ConfigError("no maps defined in [" + section + "] (add e.g. groundAwareGrid_count=1)");
}

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
	s << ") in " << std::fixed << std::setprecision(2) << seconds << " s\n";
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
		s << std::left << std::setw(int(wl) + 2) << m.label << std::setw(int(wc) + 2) << m.className
		  << std::right << std::setw(12) << fmtMs(m.median()) << std::setw(12) << fmtMs(m.p95());
		if (both)
			s << std::setw(12) << fmtMs(percentile(m.ms2D, 0.5)) << std::setw(12) << fmtMs(percentile(m.ms2D, 0.95));
		s << "\n";
	}
	return s.str();
}

// ---------------------------------------------------------------------------
Mapper::Mapper(const MapperOptions& opts) : m_opts(opts)
{
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
		throw ConfigError(m_opts.configName + ": cannot create the maps: " + firstLine(e.what()));
	}
	if (m_maps.maps.size() != m_specs.size())
		throw ConfigError("internal: CMultiMetricMap created a different number of maps than the .ini defines");
	for (size_t i = 0; i < m_specs.size(); i++)
		if (m_maps.maps[i]->GetRuntimeClass()->className != m_specs[i].className)
			throw ConfigError("internal: CMultiMetricMap map order differs from the .ini order");
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

RunSummary Mapper::run()
{
	using clk = std::chrono::steady_clock;
	const auto tStart = clk::now();
	RunSummary s;

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

	// 2. Output directory: create it and a private temporary folder inside it,
	// so nothing in DIR looks like a finished map until the very end.
	std::error_code ec;
	fs::create_directories(m_opts.outDir, ec);
	if (!fs::is_directory(m_opts.outDir))
		throw RunError("cannot create output directory " + m_opts.outDir + (ec ? ": " + ec.message() : ""));
	TmpDir tmp;
	tmp.path = (fs::path(m_opts.outDir) / (".ground-aware-mapper.tmp." + std::to_string(getpid()))).string();
	fs::remove_all(tmp.path, ec);
	if (!fs::create_directory(tmp.path, ec))
		throw RunError("output directory " + m_opts.outDir + " is not writable" + (ec ? ": " + ec.message() : ""));

	std::ofstream timing(tmp.path + "/timing.csv"), planes(tmp.path + "/ground_planes.csv");
	if (!timing || !planes) throw RunError("cannot write to " + tmp.path);
	timing << "frame,map,stage,ms\n";
	planes << "frame,a,b,c,d,nodes,status\n";
	planes << std::setprecision(9);
	timing << std::fixed << std::setprecision(4);

	s.maps.resize(m_specs.size());
	for (size_t i = 0; i < m_specs.size(); i++)
	{
		s.maps[i].label = m_specs[i].label;
		s.maps[i].className = m_specs[i].className;
	}
	int firstGA = -1;
	for (size_t i = 0; i < m_specs.size() && firstGA < 0; i++)
		if (dynamic_cast<CGroundAwareOccupancyGrid*>(m_maps.maps[i].get())) firstGA = int(i);

	// 3. Frames.
	const bool tty = stderrIsTty();
	bool progressShown = false;
	auto clearProgress = [&] {
		if (progressShown && tty) std::cerr << "\r" << std::string(78, ' ') << "\r" << std::flush;
		progressShown = false;
	};
	auto lastProgress = clk::now();
	Frame fr;
	try
	{
		while (true)
		{
			if (m_opts.stopRequested && *m_opts.stopRequested) throw RunError("interrupted");
			try
			{
				if (!reader->next(fr)) break;
			}
			catch (const std::exception& e)
			{
				throw RunError(e.what());
			}
			if (m_opts.maxFrames && fr.index >= m_opts.maxFrames) break;
			const bool is3D = IS_CLASS(*fr.obs, mrpt::obs::CObservation3DRangeScan);
			s.frames++;
			(is3D ? s.frames3D : s.frames2D)++;
			if (!fr.hasOdometry) s.framesWithoutOdometry++;

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
						m_specs[i].label + ": " + firstLine(e.what()));
				}
				const double ms = std::chrono::duration<double, std::milli>(clk::now() - t0).count();
				s.maps[i].totalMs.push_back(ms);
				(is3D ? s.maps[i].ms3D : s.maps[i].ms2D).push_back(ms);
				const std::string& L = m_specs[i].label;
				timing << fr.index << "," << L << ",total," << ms << "\n";
				if (auto* ga = dynamic_cast<CGroundAwareOccupancyGrid*>(&map); ga && is3D && ga->lastFrame().valid)
				{
					const auto& d = ga->lastFrame();
					timing << fr.index << "," << L << ",projection," << d.ms_projection << "\n"
						   << fr.index << "," << L << ",outliers," << d.ms_outliers << "\n"
						   << fr.index << "," << L << ",ground," << d.ms_ground << "\n"
						   << fr.index << "," << L << ",ism," << d.ms_ism << "\n"
						   << fr.index << "," << L << ",update," << d.ms_update << "\n";
					if (int(i) == firstGA)
					{
						const auto& det = d.detection;
						planes << fr.index << ",";
						if (det.ok() && !det.planes.empty())
						{
							const auto& p = det.plane();
							planes << p.a << "," << p.b << "," << p.c << "," << p.d;
						}
						else
							planes << ",,,";
						planes << "," << det.nodes.size() << ","
							   << gam::GroundDetection::statusName(det.status) << "\n";
					}
				}
				else if (auto* oc = dynamic_cast<COctoMapGrid2D*>(&map))
				{
					timing << fr.index << "," << L << ",octomap_insert," << oc->lastInsertionMs() << "\n"
						   << fr.index << "," << L << ",projection," << oc->lastProjectionMs() << "\n";
				}
			}

			m_lastPose = fr.robotPose;
			if (m_opts.localMap)
				for (size_t i = 0; i < m_specs.size(); i++)
					if (auto* g = dynamic_cast<COccupancyGridMap2D*>(m_maps.maps[i].get()))
						recentreGrid(*g, fr.robotPose.x(), fr.robotPose.y(), m_opts.localCells);

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
		throw;
	}
	clearProgress();
	if (s.frames == 0)
		throw RunError(
			"no usable observation in " + m_opts.rawlogPath + " (" + std::to_string(reader->entriesRead()) +
			" entries; need CObservation3DRangeScan or CObservation2DRangeScan with data)");

	timing.close();
	planes.close();
	if (!timing || !planes) throw RunError("cannot write timing.csv / ground_planes.csv in " + tmp.path);

	// 4. Maps.
	try
	{
		writeMaps(tmp.path, s);
		std::ofstream cfg(tmp.path + "/config_used.ini");
		cfg << m_opts.configText;
		if (!cfg) throw std::runtime_error("cannot write config_used.ini");
	}
	catch (const std::exception& e)
	{
		throw RunError("writing outputs: " + firstLine(e.what()));
	}
	s.files.push_back("timing.csv");
	s.files.push_back("ground_planes.csv");
	s.files.push_back("config_used.ini");

	// 5. Publish: move everything into DIR.
	for (const auto& f : s.files)
	{
		fs::rename(fs::path(tmp.path) / f, fs::path(m_opts.outDir) / f, ec);
		if (ec) throw RunError("cannot move " + f + " into " + m_opts.outDir + ": " + ec.message());
	}
	s.seconds = std::chrono::duration<double>(clk::now() - tStart).count();
	return s;
}

void Mapper::writeMaps(const std::string& dir, RunSummary& s)
{
	for (size_t i = 0; i < m_specs.size(); i++)
	{
		auto& map = *m_maps.maps[i];
		const std::string L = m_specs[i].label;
		const std::string base = dir + "/" + L;
		if (auto* oc = dynamic_cast<COctoMapGrid2D*>(&map); oc && oc->projectionOutdated())
		{
			oc->updateProjection();
		}
		if (auto* g = dynamic_cast<COccupancyGridMap2D*>(&map))
		{
			// The projection covers the whole octomap: crop it to the last window
			// (the other grids were recentred after every frame; this is a no-op for them).
			if (m_opts.localMap) recentreGrid(*g, m_lastPose.x(), m_lastPose.y(), m_opts.localCells);
			writeRosMap(*g, base + ".yaml", base + ".pgm", L + ".pgm");
			writePlainGridmapGz(*g, base + ".gridmap.gz");
			writeGridPng(*g, base + ".png");
			for (const char* ext : {".yaml", ".pgm", ".gridmap.gz", ".png"}) s.files.push_back(L + ext);
			if (auto* oc = dynamic_cast<COctoMapGrid2D*>(&map))
			{
				// The 3D octomap itself, in OctoMap's own format (octovis, octomap tools).
				// (liboctomap prints "Writing N nodes..." on stderr: keep stderr clean)
				std::cerr.flush();
				std::fflush(stderr);
				const int saved = dup(2);
				const int devnull = open("/dev/null", O_WRONLY);
				if (devnull >= 0) dup2(devnull, 2);
				auto restore = [&] {
					std::cerr.flush();
					std::fflush(stderr);
					if (saved >= 0) dup2(saved, 2), close(saved);
					if (devnull >= 0) close(devnull);
				};
				try
				{
					oc->octomap().saveMetricMapRepresentationToFile(base + "_octomap");
				}
				catch (...)
				{
					restore();
					throw;
				}
				restore();
				for (const char* ext : {"_octomap_binary.bt", "_octomap_3D.3Dscene"})
					if (fs::exists(base + ext)) s.files.push_back(L + ext);
			}
		}
		else if (auto* e = dynamic_cast<CElevation25DMap*>(&map))
		{
			e->saveAsPngs(base);
			fs::copy_file(base + "_zmax.png", base + ".png", fs::copy_options::overwrite_existing);
			for (const char* ext : {".png", "_zmax.png", "_span.png", "_count.png", "_scale.txt"})
				s.files.push_back(L + ext);
			mrpt::io::CFileGZOutputStream f;
			if (!f.open(base + ".map.gz", 6)) throw std::runtime_error("cannot write " + base + ".map.gz");
			auto ar = mrpt::serialization::archiveFrom(f);
			ar << *e;
			f.close();
			s.files.push_back(L + ".map.gz");
		}
		else
		{
			// Any other map of the .ini: MRPT's own representation + the serialized object.
			const auto before = [&] {
				std::set<std::string> n;
				for (const auto& de : fs::directory_iterator(dir)) n.insert(de.path().filename().string());
				return n;
			}();
			map.saveMetricMapRepresentationToFile(base);
			mrpt::io::CFileGZOutputStream f;
			if (!f.open(base + ".map.gz", 6)) throw std::runtime_error("cannot write " + base + ".map.gz");
			auto ar = mrpt::serialization::archiveFrom(f);
			ar << map;
			f.close();
			for (const auto& de : fs::directory_iterator(dir))
			{
				const auto n = de.path().filename().string();
				if (!before.count(n) && de.is_regular_file()) s.files.push_back(n);
			}
		}
	}
}

}  // namespace gam::mapper
