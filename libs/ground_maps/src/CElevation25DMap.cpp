#include <gam/maps/GridIO.h>
#include <gam/maps/IniFields.h>
#include <gam/maps/MapRegistry.h>
#include <gam/maps/ObservationAdapters.h>
#include <mrpt/config/CConfigFileBase.h>
#include <mrpt/img/CImage.h>
#include <mrpt/img/color_maps.h>
#include <mrpt/maps/CElevation25DMap.h>
#include <mrpt/opengl/CSetOfObjects.h>
#include <mrpt/opengl/CSetOfTriangles.h>
#include <mrpt/serialization/CArchive.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>

using namespace mrpt::maps;

// .ini names: the RTTI name first (required), then the short alias.
MAP_DEFINITION_REGISTER("mrpt::maps::CElevation25DMap,elevation25DMap", mrpt::maps::CElevation25DMap)
IMPLEMENTS_SERIALIZABLE(CElevation25DMap, CMetricMap, mrpt::maps)

namespace
{
// What tools need to know about this class (gam/maps/MapRegistry.h).
const bool kTraitsRegistered = [] {
	gam::maps::MapTraits t;
	t.className = "mrpt::maps::CElevation25DMap";
	t.sections = {
		{"_creationOpts", gam::maps::gridCreationKeys()},
		{"_insertOpts", gam::maps::ini::keys<CElevation25DMap::TInsertionOptions>()}};
	t.writeOutputs = [](CMetricMap& m, const gam::maps::OutputContext& ctx, std::vector<std::string>& files) {
		const auto& e = dynamic_cast<const CElevation25DMap&>(m);
		const std::string base = ctx.dir + "/" + ctx.label;
		e.saveAsPngs(base);
		std::filesystem::copy_file(
			base + "_zmax.png", base + ".png", std::filesystem::copy_options::overwrite_existing);
		for (const char* ext : {".png", "_zmax.png", "_span.png", "_count.png", "_scale.txt"})
			files.push_back(ctx.label + ext);
		gam::maps::writeSerializedGz(e, base + ".map.gz");
		files.push_back(ctx.label + ".map.gz");
	};
	gam::maps::registerMapTraits(std::move(t));
	return true;
}();
}  // namespace

CElevation25DMap::TMapDefinition::TMapDefinition() = default;

void CElevation25DMap::TMapDefinition::loadFromConfigFile_map_specific(
	const mrpt::config::CConfigFileBase& source, const std::string& sectionNamePrefix)
{
	const std::string sC = sectionNamePrefix + "_creationOpts";
	gam::maps::ini::loadGridExtent(source, sC, min_x, max_x, min_y, max_y, resolution);
	// ElevationGrid has its own (smaller) cell limit: refuse before allocating.
	gam::maps::ini::checkInSection(sC, [&] {
		gam::GridGeometry g;
		g.x_min = min_x;
		g.y_min = min_y;
		g.resolution = resolution;
		g.nx = int(std::lround((max_x - min_x) / resolution));
		g.ny = int(std::lround((max_y - min_y) / resolution));
		g.validate();
	});
	insertionOpts.loadFromConfigFile(source, sectionNamePrefix + "_insertOpts");
}

void CElevation25DMap::TMapDefinition::dumpToTextStream_map_specific(std::ostream& out) const
{
	out << "min_x=" << min_x << " max_x=" << max_x << " min_y=" << min_y << " max_y=" << max_y
		<< " resolution=" << resolution << "\n";
	insertionOpts.dumpToTextStream(out);
}

mrpt::maps::CMetricMap* CElevation25DMap::internal_CreateFromMapDefinition(const TMetricMapInitializer& _def)
{
	const auto& def = dynamic_cast<const CElevation25DMap::TMapDefinition&>(_def);
	auto* m = new CElevation25DMap(def.min_x, def.max_x, def.min_y, def.max_y, def.resolution);
	m->setInsertionOptions(def.insertionOpts);
	return m;
}

// ---------------------------------------------------------------------------
void CElevation25DMap::TInsertionOptions::loadFromConfigFile(
	const mrpt::config::CConfigFileBase& source, const std::string& section)
{
	gam::maps::ini::loadThenCheck(*this, source, section, [this] { validate(); });
}

void CElevation25DMap::TInsertionOptions::saveToConfigFile(
	mrpt::config::CConfigFileBase& target, const std::string& section) const
{
	gam::maps::ini::save(*this, target, section);
}

void CElevation25DMap::TInsertionOptions::validate() const
{
	gam::checkParamRanges(*this, "");
	projection.validate();
}

void CElevation25DMap::setInsertionOptions(const TInsertionOptions& o)
{
	o.validate();
	m_options = o;
}

// ---------------------------------------------------------------------------
CElevation25DMap::CElevation25DMap(double x_min, double x_max, double y_min, double y_max, double resolution)
{
	setSize(x_min, x_max, y_min, y_max, resolution);
}

void CElevation25DMap::setSize(double x_min, double x_max, double y_min, double y_max, double res)
{
	if (!(res > 0)) throw std::invalid_argument("CElevation25DMap: resolution must be > 0");
	if (!(x_max > x_min) || !(y_max > y_min))
		throw std::invalid_argument("CElevation25DMap: need min_x < max_x and min_y < max_y");
	// Cell counts must fit an int before GridGeometry::validate() checks the total.
	if (!((x_max - x_min) / res < 1e9) || !((y_max - y_min) / res < 1e9))
		throw std::invalid_argument("CElevation25DMap: grid extent / resolution is too large");
	gam::GridGeometry g;
	g.x_min = x_min;
	g.y_min = y_min;
	g.resolution = res;
	g.nx = int(std::lround((x_max - x_min) / res));
	g.ny = int(std::lround((y_max - y_min) / res));
	m_grid.resize(g);
}

void CElevation25DMap::internal_clear() { m_grid.clear(); }

bool CElevation25DMap::isEmpty() const { return m_grid.observedCount() == 0; }

void CElevation25DMap::finishInsertion()
{
	m_grid.insert(m_bins, m_options.outliers);
	m_bins.clear();
	if (m_options.idw.radius_cells > 0) m_grid.interpolateIdw(m_options.idw);
}

bool CElevation25DMap::internal_insertObservation(
	const mrpt::obs::CObservation& obs, const std::optional<const mrpt::poses::CPose3D>& robotPose)
{
	m_bins.clear();
	size_t n = 0;
	if (!gam::maps::binObservation(
			obs, robotPose ? *robotPose : mrpt::poses::CPose3D(), m_options.projection, m_grid, m_projector, m_bins,
			&n))
		return false;
	finishInsertion();
	return n > 0;
}

size_t CElevation25DMap::insertPointCloud(const mrpt::maps::CPointsMap& pts, const mrpt::poses::CPose3D& pose)
{
	m_bins.clear();
	gam::ProjectionFilter f = m_options.projection;
	f.min_range = 0;  // ranges mean nothing for an already registered cloud
	f.max_range = std::numeric_limits<float>::max();
	gam::maps::binPointCloud(pts, pose, f, m_grid, m_bins);
	const size_t n = m_bins.size();
	finishInsertion();
	return n;
}

bool CElevation25DMap::getMinMaxHeight(float& zmin, float& zmax) const
{
	if (isEmpty()) return false;
	zmin = std::numeric_limits<float>::infinity();
	zmax = -zmin;
	for (uint32_t i : m_grid.observedCells())
	{
		zmin = std::min(zmin, m_grid.cell(i).z_min);
		zmax = std::max(zmax, m_grid.cell(i).z_max);
	}
	return true;
}

std::string CElevation25DMap::asString() const
{
	const auto& g = m_grid.geometry();
	std::ostringstream s;
	s << "CElevation25DMap " << g.nx << "x" << g.ny << " cells at " << g.resolution << " m, x[" << g.x_min << ","
	  << g.x_max() << "] y[" << g.y_min << "," << g.y_max() << "], " << m_grid.observedCount() << " observed cells";
	return s.str();
}

// ---------------------------------------------------------------------------
// Serialization: v0 = geometry, insertion options, generic params, observed cells.
// v0: cells with the sum of z^2; v1: with the sum of squared deviations from
// the mean (ElevationCell::z_m2).
uint8_t CElevation25DMap::serializeGetVersion() const { return 1; }

void CElevation25DMap::serializeTo(mrpt::serialization::CArchive& out) const
{
	const auto& g = m_grid.geometry();
	out << g.x_min << g.y_min << g.resolution << int32_t(g.nx) << int32_t(g.ny);
	const auto& o = m_options;
	out << o.projection.z_min << o.projection.z_max << o.projection.min_range << o.projection.max_range
		<< int32_t(o.projection.decimation) << o.outliers.enabled << o.outliers.sigmas << int32_t(o.outliers.min_count)
		<< int32_t(o.idw.radius_cells) << o.idw.power << int32_t(o.idw.min_neighbours);
	out << genericMapParams;
	out << uint32_t(m_grid.observedCount());
	for (uint32_t i : m_grid.observedCells())
	{
		const auto& c = m_grid.cell(i);
		out << i << c.z_min << c.z_max << c.count << c.z_sum << c.z_m2;
	}
}

void CElevation25DMap::serializeFrom(mrpt::serialization::CArchive& in, uint8_t version)
{
	switch (version)
	{
		case 0:
		case 1: {
			gam::GridGeometry g;
			int32_t nx, ny;
			in >> g.x_min >> g.y_min >> g.resolution >> nx >> ny;
			g.nx = nx;
			g.ny = ny;
			m_grid.resize(g);  // validates
			TInsertionOptions o;
			int32_t dec, omc, idr, idn;
			in >> o.projection.z_min >> o.projection.z_max >> o.projection.min_range >> o.projection.max_range >> dec >>
				o.outliers.enabled >> o.outliers.sigmas >> omc >> idr >> o.idw.power >> idn;
			o.projection.decimation = dec;
			o.outliers.min_count = uint32_t(omc);
			o.idw.radius_cells = idr;
			o.idw.min_neighbours = idn;
			setInsertionOptions(o);  // validates
			in >> genericMapParams;
			uint32_t n;
			in >> n;
			if (n > g.cellCount())
				throw std::runtime_error("CElevation25DMap: corrupt stream (more cells than the grid)");
			gam::BinnedPoints none;
			for (uint32_t k = 0; k < n; k++)
			{
				uint32_t i;
				gam::ElevationCell c;
				in >> i >> c.z_min >> c.z_max >> c.count >> c.z_sum >> c.z_m2;
				if (i >= g.cellCount() || c.count == 0)
					throw std::runtime_error("CElevation25DMap: corrupt stream (bad cell)");
				if (version == 0)  // the sum of z^2: as precise as it was written
					c.z_m2 = float(std::max(0.0, double(c.z_m2) - double(c.z_sum) * double(c.z_sum) / double(c.count)));
				m_grid.restoreCell(i, c);
			}
			if (o.idw.radius_cells > 0) m_grid.interpolateIdw(o.idw);
		}
		break;
		default: MRPT_THROW_UNKNOWN_SERIALIZATION_VERSION(version);
	}
}

// ---------------------------------------------------------------------------
void CElevation25DMap::getVisualizationInto(mrpt::opengl::CSetOfObjects& outObj) const
{
	if (!genericMapParams.enableSaveAs3DObject) return;
	float zlo, zhi;
	if (!getMinMaxHeight(zlo, zhi)) return;
	const auto& g = m_grid.geometry();
	const float span = std::max(1e-3f, zhi - zlo);
	auto tris = mrpt::opengl::CSetOfTriangles::Create();
	tris->setName("CElevation25DMap");
	tris->reserve(m_grid.observedCount() * 10);
	const float h = float(g.resolution) * 0.5f;
	using P = mrpt::math::TPoint3Df;
	for (uint32_t i : m_grid.observedCells())
	{
		const auto& c = m_grid.cell(i);
		const float x = float(g.cx(int(i % uint32_t(g.nx)))), y = float(g.cy(int(i / uint32_t(g.nx))));
		const float z0 = c.z_min, z1 = std::max(c.z_max, c.z_min + 0.25f * h);
		const auto col = mrpt::img::colormap(mrpt::img::cmJET, (c.z_max - zlo) / span);
		const P v[8] = {{x - h, y - h, z0}, {x + h, y - h, z0}, {x + h, y + h, z0}, {x - h, y + h, z0},
						{x - h, y - h, z1}, {x + h, y - h, z1}, {x + h, y + h, z1}, {x - h, y + h, z1}};
		// Top and the four sides of the column (the bottom is never seen).
		static const int faces[5][4] = {{4, 5, 6, 7}, {0, 1, 5, 4}, {1, 2, 6, 5}, {2, 3, 7, 6}, {3, 0, 4, 7}};
		for (const auto& f : faces)
			for (int t = 0; t < 2; t++)
			{
				mrpt::opengl::TTriangle tri(v[f[0]], v[f[1 + t]], v[f[2 + t]]);
				tri.setColor(col);
				tris->insertTriangle(tri);
			}
	}
	outObj.insert(tris);
}

void CElevation25DMap::saveAsPngs(const std::string& prefix) const
{
	const auto& g = m_grid.geometry();
	float zlo = 0, zhi = 1;
	getMinMaxHeight(zlo, zhi);
	float spanMax = 1e-3f;
	uint32_t countMax = 1;
	for (uint32_t i : m_grid.observedCells())
	{
		spanMax = std::max(spanMax, m_grid.cell(i).span());
		countMax = std::max(countMax, m_grid.cell(i).count);
	}
	mrpt::img::CImage zmax(g.nx, g.ny, mrpt::img::CH_RGB), span(g.nx, g.ny, mrpt::img::CH_RGB),
		count(g.nx, g.ny, mrpt::img::CH_RGB);
	for (auto* im : {&zmax, &span, &count}) im->filledRectangle(0, 0, g.nx - 1, g.ny - 1, mrpt::img::TColor(0, 0, 0));
	const float zr = std::max(1e-3f, zhi - zlo);
	for (uint32_t i : m_grid.observedCells())
	{
		const auto& c = m_grid.cell(i);
		const int cx = int(i % uint32_t(g.nx)), row = g.ny - 1 - int(i / uint32_t(g.nx));  // +y up
		zmax.setPixel(cx, row, mrpt::img::colormap(mrpt::img::cmJET, (c.z_max - zlo) / zr));
		span.setPixel(cx, row, mrpt::img::colormap(mrpt::img::cmHOT, c.span() / spanMax));
		count.setPixel(
			cx, row, mrpt::img::colormap(mrpt::img::cmHOT, std::log1p(float(c.count)) / std::log1p(float(countMax))));
	}
	if (!zmax.saveToFile(prefix + "_zmax.png") || !span.saveToFile(prefix + "_span.png") ||
		!count.saveToFile(prefix + "_count.png"))
		throw std::runtime_error("CElevation25DMap: cannot write PNGs with prefix " + prefix);
	std::ofstream f(prefix + "_scale.txt");
	// The file name only: the directory may be temporary (the mapper writes into a
	// hidden folder first), and outputs must not depend on it.
	const std::string stem =
		prefix.substr(prefix.find_last_of('/') == std::string::npos ? 0 : prefix.find_last_of('/') + 1);
	f << "# colour scales of " << stem << "_*.png (one pixel per cell, +y up, black = no data)\n"
	  << "zmax_png: jet colormap, blue = " << zlo << " m, red = " << zhi << " m\n"
	  << "span_png: hot colormap, black = 0 m, white = " << spanMax << " m\n"
	  << "count_png: hot colormap of log(1+N_z), white = " << countMax << " samples\n"
	  << "grid: x_min " << g.x_min << " y_min " << g.y_min << " resolution " << g.resolution << " nx " << g.nx << " ny "
	  << g.ny << "\n";
}

void CElevation25DMap::saveMetricMapRepresentationToFile(const std::string& prefix) const { saveAsPngs(prefix); }
