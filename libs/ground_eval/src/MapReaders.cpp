// Ground-aware mapping for MRPT -- map evaluation: the readers of the map_server map
// and of the ground truth (see MapReaders.h).
#include "gam/eval/MapReaders.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <fstream>
#include <map>
#include <sstream>

#include "Csv.h"
#include "PathNames.h"
#include "gam/common/Strings.h"

namespace gam::eval
{
namespace
{
using gam::trim;

using detail::Columns;
using detail::readCsv;
using detail::splitCsv;
using detail::toDouble;
using detail::toInt;

/** yaml keys of a map_server file (flat "key: value" lines). */
std::map<std::string, std::string> readYamlKeys(const std::string& path)
{
	std::ifstream f(path);
	if (!f) throw Error("cannot open " + path);
	std::map<std::string, std::string> kv;
	std::string line;
	while (std::getline(f, line))
	{
		const auto h = line.find('#');
		if (h != std::string::npos) line = line.substr(0, h);
		if (trim(line).empty()) continue;
		const auto c = line.find(':');
		if (c == std::string::npos) throw Error(path + ": not a map_server yaml (line '" + trim(line) + "')");
		kv[trim(line.substr(0, c))] = trim(line.substr(c + 1));
	}
	return kv;
}

void parseOrigin(const std::string& path, const std::string& v, double& x, double& y, double& yaw)
{
	if (v.size() < 2 || v.front() != '[' || v.back() != ']') throw Error(path + ": bad origin '" + v + "'");
	std::string in = v.substr(1, v.size() - 2);
	for (auto& ch : in)
		if (ch == ',') ch = ' ';
	std::istringstream ss(in);
	std::string a, b, c;
	if (!(ss >> a >> b >> c)) throw Error(path + ": bad origin '" + v + "'");
	x = toDouble(a, path + ": origin");
	y = toDouble(b, path + ": origin");
	yaw = toDouble(c, path + ": origin");
}

void readPgm(const std::string& path, int& w, int& h, std::vector<uint8_t>& px)
{
	std::ifstream f(path, std::ios::binary);
	if (!f) throw Error("cannot open " + path);
	auto token = [&]() {
		std::string t;
		char c;
		while (f.get(c))
		{
			if (t.empty() && c == '#')
			{
				std::string dummy;
				std::getline(f, dummy);
				continue;
			}
			if (std::isspace((unsigned char)c))
			{
				if (!t.empty()) break;
				continue;
			}
			t += c;
		}
		return t;
	};
	if (token() != "P5") throw Error(path + ": not a binary PGM (P5)");
	int maxval = 0;
	try
	{
		w = std::stoi(token());
		h = std::stoi(token());
		maxval = std::stoi(token());
	}
	catch (...)
	{
		throw Error(path + ": bad PGM header");
	}
	if (w <= 0 || h <= 0 || w > 100000 || h > 100000) throw Error(path + ": bad PGM size");
	if (maxval != 255) throw Error(path + ": PGM maxval " + std::to_string(maxval) + " (only 255 is supported)");
	px.resize(size_t(w) * size_t(h));
	f.read(reinterpret_cast<char*>(px.data()), std::streamsize(px.size()));
	if (f.gcount() != std::streamsize(px.size())) throw Error(path + ": truncated PGM");
}

/** The label whose labelName() is `name`; false if there is none. */
bool labelFromName(const std::string& name, Label& l)
{
	for (Label c : {Label::Free, Label::Obstacle, Label::Drop, Label::Unobserved})
		if (name == labelName(c))
		{
			l = c;
			return true;
		}
	return false;
}
}  // namespace

double RosMap::pOcc(int col, int rowFromBottom) const
{
	const uint8_t v = pixels[size_t(height - 1 - rowFromBottom) * size_t(width) + size_t(col)];
	const double p = negate ? v / 255.0 : (255.0 - v) / 255.0;
	if (mode == "trinary")
	{
		if (p > occupied_thresh) return 1.0;
		if (p < free_thresh) return 0.0;
		return 0.5;
	}
	return p;
}

RosMap loadRosMap(const std::string& yamlPath)
{
	const auto kv = readYamlKeys(yamlPath);
	RosMap m;
	m.yamlPath = yamlPath;
	auto need = [&](const char* k) -> const std::string& {
		auto it = kv.find(k);
		if (it == kv.end()) throw Error(yamlPath + ": missing key '" + k + "'");
		return it->second;
	};
	std::string image = need("image");
	if (image.size() >= 2 && (image.front() == '"' || image.front() == '\'') && image.back() == image.front())
		image = image.substr(1, image.size() - 2);
	m.imagePath = (!image.empty() && image[0] == '/') ? image : detail::dirOf(yamlPath) + image;
	m.resolution = toDouble(need("resolution"), yamlPath + ": resolution");
	if (!(m.resolution > 0)) throw Error(yamlPath + ": resolution must be > 0");
	parseOrigin(yamlPath, need("origin"), m.origin_x, m.origin_y, m.origin_yaw);
	if (std::abs(m.origin_yaw) > 1e-9) throw Error(yamlPath + ": rotated maps (origin yaw != 0) are not supported");
	if (kv.count("mode")) m.mode = kv.at("mode");
	if (m.mode != "scale" && m.mode != "trinary")
		throw Error(yamlPath + ": mode '" + m.mode + "' is not supported (scale or trinary)");
	if (kv.count("negate"))
	{
		m.negate = toInt(kv.at("negate"), yamlPath + ": negate");
		if (m.negate != 0 && m.negate != 1) throw Error(yamlPath + ": negate must be 0 or 1");
	}
	if (kv.count("occupied_thresh"))
		m.occupied_thresh = toDouble(kv.at("occupied_thresh"), yamlPath + ": occupied_thresh");
	if (kv.count("free_thresh")) m.free_thresh = toDouble(kv.at("free_thresh"), yamlPath + ": free_thresh");
	if (!(m.free_thresh >= 0 && m.free_thresh <= m.occupied_thresh && m.occupied_thresh <= 1))
		throw Error(yamlPath + ": need 0 <= free_thresh <= occupied_thresh <= 1");
	readPgm(m.imagePath, m.width, m.height, m.pixels);
	return m;
}

const GtObject* GroundTruth::object(int id) const
{
	for (const auto& o : objects)
		if (o.id == id) return &o;
	return nullptr;
}

GroundTruth loadGroundTruth(const std::string& prefix)
{
	GroundTruth gt;
	gt.prefix = prefix;
	{
		const std::string yp = prefix + "_gt.yaml";
		const auto kv = readYamlKeys(yp);
		auto it = kv.find("resolution");
		if (it == kv.end()) throw Error(yp + ": missing key 'resolution'");
		gt.resolution = toDouble(it->second, yp + ": resolution");
		if (!(gt.resolution > 0)) throw Error(yp + ": resolution must be > 0");
	}
	{
		auto header = [](const std::string& line) {
			const auto h = splitCsv(line);
			return h.size() >= 4 && trim(h[0]) == "id" && trim(h[3]) == "category";
		};
		auto row = [&](const Columns& c, const std::string& at) {
			if (c.size() < 4) throw Error(at + ": too few columns");
			GtObject o;
			o.id = toInt(c[0], at + ": id");
			o.name = c[1];
			o.type = c[2];
			o.category = trim(c[3]);
			gt.objects.push_back(o);
		};
		readCsv(prefix + "_gt_objects.csv", header, "id,name,type,category,...", row);
	}
	const std::string lp = prefix + "_gt_labels.csv";
	struct Row
	{
		int ix, iy, id;
		double x, y;
		Label l;
	};
	std::vector<Row> rows;
	auto header = [](const std::string& line) { return trim(line).rfind("ix,iy,x,y,label,object_id", 0) == 0; };
	auto row = [&](const Columns& c, const std::string& at) {
		if (c.size() < 6) throw Error(at + ": too few columns");
		Row r;
		r.ix = toInt(c[0], at + ": ix");
		r.iy = toInt(c[1], at + ": iy");
		r.x = toDouble(c[2], at + ": x");
		r.y = toDouble(c[3], at + ": y");
		const std::string l = trim(c[4]);
		if (!labelFromName(l, r.l)) throw Error(at + ": unknown label '" + l + "'");
		r.id = toInt(c[5], at + ": object_id");
		if (r.ix < 0 || r.iy < 0 || r.ix > 100000 || r.iy > 100000) throw Error(at + ": bad cell index");
		rows.push_back(r);
		gt.nx = std::max(gt.nx, r.ix + 1);
		gt.ny = std::max(gt.ny, r.iy + 1);
	};
	readCsv(lp, header, "ix,iy,x,y,label,object_id,category", row);
	if (rows.empty()) throw Error(lp + ": no cells");
	const size_t n = size_t(gt.nx) * size_t(gt.ny);
	if (rows.size() != n)
		throw Error(
			lp + ": " + std::to_string(rows.size()) + " rows, expected " + std::to_string(gt.nx) + "x" +
			std::to_string(gt.ny));
	gt.x.assign(n, std::nan(""));
	gt.y.assign(n, std::nan(""));
	gt.label.assign(n, Label::Unobserved);
	gt.objectId.assign(n, 0);
	for (const auto& r : rows)
	{
		const size_t i = gt.idx(r.ix, r.iy);
		if (!std::isnan(gt.x[i]))
			throw Error(lp + ": cell " + std::to_string(r.ix) + "," + std::to_string(r.iy) + " twice");
		gt.x[i] = r.x;
		gt.y[i] = r.y;
		gt.label[i] = r.l;
		gt.objectId[i] = r.id;
		if (r.id != 0 && !gt.object(r.id))
			throw Error(lp + ": object_id " + std::to_string(r.id) + " is not in " + prefix + "_gt_objects.csv");
	}
	return gt;
}

}  // namespace gam::eval
