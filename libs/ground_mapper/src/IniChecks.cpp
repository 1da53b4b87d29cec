// ground-aware-mapper's .ini checks: the map definitions of a [map]-style
// section, read the way CMultiMetricMap reads them, plus what MRPT does not
// check: unknown map types, unknown sub-sections and keys of this project's
// map classes (from their traits, gam/maps/MapRegistry.h), keys no loader
// read, and the output labels.
#include <gam/mapper/Errors.h>
#include <gam/mapper/Mapper.h>
#include <gam/maps/MapRegistry.h>
#include <mrpt/maps/TMetricMapTypesRegistry.h>
#include <mrpt/maps/registerGroundAwareMaps.h>

#include <algorithm>
#include <cstdio>
#include <set>

#include "gam/common/Strings.h"

using namespace mrpt::maps;

namespace gam::mapper
{
namespace
{

bool validLabel(const std::string& l)
{
	if (l.empty() || l[0] == '.' || l.size() > 100) return false;
	return std::all_of(
		l.begin(), l.end(), [](char c) { return std::isalnum((unsigned char)c) || c == '_' || c == '-' || c == '.'; });
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
		return m_read.count(gam::toLower(sec) + "\n" + gam::toLower(key)) > 0;
	}

   protected:
	void writeString(const std::string&, const std::string&, const std::string&) override
	{
		throw std::logic_error("RecordingConfig is read-only");
	}
	std::string readString(
		const std::string& sec, const std::string& name, const std::string& def, bool failIfNotFound) const override
	{
		m_read.insert(gam::toLower(sec) + "\n" + gam::toLower(name));
		return m_in.read_string(sec, name, def, failIfNotFound);
	}

   private:
	const mrpt::config::CConfigFileBase& m_in;
	mutable std::set<std::string> m_read;
};

/** Keys this project's maps once read in the sub-section `suffix` (e.g.
 * "_groundOpts") and no longer do: a rule of the default that changed no map
 * on any camera was retired with its key (issue #27, doc/rules.md). An .ini
 * written for an older version still runs; the mapper says the key is
 * ignored, and why. nullptr: not a retired key of that sub-section. */
const char* retiredKeyReason(const std::string& suffix, const std::string& key)
{
	struct Retired
	{
		const char *suffix, *key, *why;
	};
	static const Retired kRetired[] = {
		{"_groundOpts", "max_drop_ray_length", "drop rays are no longer cut (the cut changed no map)"},
		{"_groundOpts", "max_fit_rms", "a local fit is judged by its tilt (N_th) alone (the RMS limit changed no map)"},
		{"_groundOpts", "missing_floor_min_range",
		 "a missing-floor region needs seen floor nearer along its rays, which covers it"},
		{"_groundOpts", "min_drop_points", "a drop takes min_obstacle_points, as an obstacle does"},
		{"_groundOpts", "drop_ray_min_points", "a drop that counts (min_obstacle_points) casts its drop ray"},
	};
	for (const Retired& r : kRetired)
		if (suffix == r.suffix && gam::iequals(key, r.key)) return r.why;
	return nullptr;
}

/** Every sub-section `<prefix>_*` of a map must be one its class declares, with
 * keys it declares (an empty key list accepts any key) or retired keys (a
 * warning each). Throws ConfigError. */
void checkSections(
	const mrpt::config::CConfigFileBase& ini, const MapSpec& sp, const std::vector<gam::maps::IniSection>& declared,
	std::vector<std::string>* warnings)
{
	std::vector<std::string> sections;
	ini.getAllSections(sections);
	for (const auto& sec : sections)
	{
		if (sec.size() <= sp.prefix.size() + 1 || sec.compare(0, sp.prefix.size() + 1, sp.prefix + "_") != 0) continue;
		const std::string suffix = sec.substr(sp.prefix.size());
		const auto it = std::find_if(
			declared.begin(), declared.end(), [&](const gam::maps::IniSection& d) { return d.suffix == suffix; });
		if (it == declared.end())
		{
			std::string allowed;
			for (const auto& d : declared) allowed += (allowed.empty() ? "" : ", ") + sp.prefix + d.suffix;
			throw ConfigError("unknown section [" + sec + "] (" + sp.className + " reads " + allowed + ")");
		}
		if (it->keys.empty()) continue;
		std::vector<std::string> secKeys;
		ini.getAllKeys(sec, secKeys);
		for (const auto& k : secKeys)
		{
			if (const char* why = retiredKeyReason(suffix, k))
			{
				if (warnings)
					warnings->push_back(
						"[" + sec + "] key '" + k + "' was retired and is ignored: " + why + " (doc/rules.md)");
				continue;
			}
			if (std::none_of(
					it->keys.begin(), it->keys.end(), [&](const std::string& a) { return gam::iequals(a, k); }))
			{
				std::string accepted;
				for (const auto& a : it->keys) accepted += (accepted.empty() ? "" : " ") + a;
				throw ConfigError(
					"[" + sec + "] unknown key '" + k + "' (" + sp.className + " accepts: " + accepted + ")");
			}
		}
	}
}
}  // namespace

// ---------------------------------------------------------------------------
void loadMapDefinitions(
	const mrpt::config::CConfigFileBase& iniIn, const std::string& section, TSetOfMetricMapInitializers& inits,
	std::vector<MapSpec>& specs, std::vector<std::string>* warnings)
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
		if (k.size() <= suffix.size() || k.compare(k.size() - suffix.size(), suffix.size(), suffix) != 0) continue;
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
		const std::string raw = gam::stripIniComment(ini.read_string(section, countKey, "0", false));
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

			// Unknown keys and sub-sections of this project's map classes (those
			// whose traits declare their sections).
			const gam::maps::MapTraits* traits = gam::maps::findMapTraits(sp.className);
			const bool ours = traits && !traits->sections.empty();
			if (ours) checkSections(ini, sp, traits->sections, warnings);

			try
			{
				mi->loadFromConfigFile(ini, sp.prefix);
			}
			catch (const std::exception& e)
			{
				throw ConfigError(conciseError(e.what()));
			}

			std::string defLabel = name + "_" + nn;
			std::replace(defLabel.begin(), defLabel.end(), ':', '_');
			sp.label = gam::stripIniComment(ini.read_string(sp.prefix + "_creationOpts", "label", defLabel, false));

			// Keys the map's own loader never read: typos (errors for this project's
			// maps, warnings for stock MRPT maps, whose loaders may read keys conditionally).
			{
				std::vector<std::string> sections;
				ini.getAllSections(sections);
				for (const auto& sec : sections)
				{
					if (sec.size() <= sp.prefix.size() + 1 ||
						gam::toLower(sec.substr(0, sp.prefix.size() + 1)) != gam::toLower(sp.prefix + "_"))
						continue;
					std::vector<std::string> secKeys;
					ini.getAllKeys(sec, secKeys);
					for (const auto& k : secKeys)
					{
						if (ini.wasRead(sec, k) || (ours && retiredKeyReason(sec.substr(sp.prefix.size()), k)))
							continue;
						const std::string msg = "[" + sec + "] key '" + k + "' is not used by " + sp.className;
						if (ours) throw ConfigError(msg);
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
	if (specs.empty()) throw ConfigError("no maps defined in [" + section + "] (add e.g. groundAwareGrid_count=1)");
}

}  // namespace gam::mapper
