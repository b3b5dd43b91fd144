// SPDX-License-Identifier: Apache-2.0
#include "daemon/maps/ogr_map_writer.hpp"

#include <gdal_priv.h>
#include <ogr_spatialref.h>
#include <ogrsf_frmts.h>

#include <stdexcept>

namespace weedspray::daemon::maps {

namespace fs = std::filesystem;

// Named, not anonymous: OgrMapWriter::Impl holds these, and GCC's -Wsubobject-linkage flags a
// class defined outside the main file that holds an anonymous type; in a unity build every file
// of a batch is such a file.
namespace ogr_detail {

std::string gdal_error() {
  const char* message = CPLGetLastErrorMsg();
  return message != nullptr && *message != '\0' ? message : "unknown GDAL error";
}

struct DatasetCloser {
  void operator()(GDALDataset* ds) const { GDALClose(ds); }
};
using Dataset = std::unique_ptr<GDALDataset, DatasetCloser>;

struct FeatureDeleter {
  void operator()(OGRFeature* f) const { OGRFeature::DestroyFeature(f); }
};

void add_field(OGRLayer* layer, const char* name, OGRFieldType type, const fs::path& where) {
  OGRFieldDefn field(name, type);
  if (type == OFTString) field.SetWidth(24);
  if (layer->CreateField(&field) != OGRERR_NONE)
    throw std::runtime_error(where.string() + ": cannot add field " + name + ": " + gdal_error());
}

// A layer and a reusable feature: features are filled and written one at a time (streaming:
// the stretches of a day never sit in memory).
struct Layer {
  fs::path file;
  OGRLayer* layer = nullptr;
  std::unique_ptr<OGRFeature, FeatureDeleter> feature;

  void write(std::unique_ptr<OGRPolygon> polygon) {
    feature->SetGeometryDirectly(polygon.release());
    feature->SetFID(OGRNullFID);
    if (layer->CreateFeature(feature.get()) != OGRERR_NONE)
      throw std::runtime_error(file.string() + ": cannot write a feature: " + gdal_error());
  }
};

}  // namespace ogr_detail

namespace {

using ogr_detail::add_field;
using ogr_detail::Dataset;
using ogr_detail::gdal_error;
using ogr_detail::Layer;

std::unique_ptr<OGRPolygon> polygon(const std::vector<LatLon>& ring_points) {
  auto ring = std::make_unique<OGRLinearRing>();
  ring->setNumPoints(static_cast<int>(ring_points.size()) + 1, FALSE);
  int i = 0;
  for (const LatLon& p : ring_points) ring->setPoint(i++, p.longitude_deg, p.latitude_deg);
  ring->setPoint(i, ring_points.front().longitude_deg, ring_points.front().latitude_deg);
  auto poly = std::make_unique<OGRPolygon>();
  poly->addRingDirectly(ring.release());
  return poly;
}

}  // namespace

MapFormat parse_map_format(const std::string& name) {
  if (name == "geojson") return MapFormat::kGeoJson;
  if (name == "gpkg") return MapFormat::kGpkg;
  if (name == "shp") return MapFormat::kShapefile;
  throw std::invalid_argument("--format " + name + ": expected geojson, gpkg or shp");
}

struct OgrMapWriter::Impl {
  MapFormat format;
  OGRSpatialReference wgs84;
  std::vector<Dataset> datasets;  // one (GPKG, Shapefile folder) or one per layer (GeoJSON)
  Layer sprayed, density;
  bool in_transaction = false;
  bool board_field = false;
  std::vector<LatLon> ring;  // reused for each polygon

  GDALDriver* driver(const char* name) {
    GDALDriver* d = GetGDALDriverManager()->GetDriverByName(name);
    if (d == nullptr) throw std::runtime_error(std::string("GDAL has no ") + name + " driver");
    return d;
  }

  Layer make_layer(GDALDataset* ds, const fs::path& file, const char* name, char** options) {
    Layer l;
    l.file = file;
    l.layer = ds->CreateLayer(name, &wgs84, wkbPolygon, options);
    if (l.layer == nullptr)
      throw std::runtime_error(file.string() + ": cannot create layer " + name + ": " +
                               gdal_error());
    return l;
  }
};

OgrMapWriter::OgrMapWriter(MapFormat format, const fs::path& out, bool overwrite, bool board_field)
    : impl_(std::make_unique<Impl>()) {
  GDALAllRegister();
  Impl& m = *impl_;
  m.format = format;
  m.board_field = board_field;
  m.wgs84.importFromEPSG(4326);
  // x = longitude, y = latitude, as GeoJSON and every GIS expect on disk.
  m.wgs84.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);

  const bool folder = format != MapFormat::kGpkg;
  std::error_code ec;
  if (fs::exists(out, ec)) {
    if (!overwrite) throw std::runtime_error(out.string() + ": exists (--overwrite replaces it)");
    if (folder != fs::is_directory(out, ec))
      throw std::runtime_error(out.string() + ": exists and is " +
                               (folder ? "not a folder" : "a folder") + "; not replaced");
    if (folder) {
      // Only this export's own files go; anything else in the folder stays.
      for (const char* layer : {"sprayed", "weed_density"}) {
        for (const char* ext : {".geojson", ".shp", ".shx", ".dbf", ".prj", ".cpg"}) {
          fs::remove(out / (std::string(layer) + ext), ec);
        }
      }
    } else {
      fs::remove(out, ec);
    }
  }
  if (folder) {
    fs::create_directories(out, ec);
    if (ec) throw std::runtime_error(out.string() + ": " + ec.message());
  }

  auto create = [&](GDALDriver* driver, const fs::path& path) {
    Dataset ds(driver->Create(path.c_str(), 0, 0, 0, GDT_Unknown, nullptr));
    if (!ds) throw std::runtime_error(path.string() + ": cannot be created: " + gdal_error());
    m.datasets.push_back(std::move(ds));
    return m.datasets.back().get();
  };
  char** layer_options = nullptr;
  if (format == MapFormat::kGeoJson) {
    // 8 decimals of a degree: ~1 mm, and a third less text than GDAL's default 15 digits.
    layer_options = CSLSetNameValue(layer_options, "COORDINATE_PRECISION", "8");
    GDALDriver* driver = m.driver("GeoJSON");
    m.sprayed = m.make_layer(create(driver, out / "sprayed.geojson"), out / "sprayed.geojson",
                             "sprayed", layer_options);
    m.density = m.make_layer(create(driver, out / "weed_density.geojson"),
                             out / "weed_density.geojson", "weed_density", layer_options);
  } else {
    GDALDataset* ds = create(m.driver(format == MapFormat::kGpkg ? "GPKG" : "ESRI Shapefile"), out);
    const fs::path sprayed_file = folder ? out / "sprayed.shp" : out;
    const fs::path density_file = folder ? out / "weed_density.shp" : out;
    m.sprayed = m.make_layer(ds, sprayed_file, "sprayed", nullptr);
    m.density = m.make_layer(ds, density_file, "weed_density", nullptr);
    // GeoPackage is SQLite: one transaction for the whole export instead of one per feature.
    if (format == MapFormat::kGpkg) {
      if (ds->StartTransaction() != OGRERR_NONE)
        throw std::runtime_error(out.string() + ": cannot start a transaction: " + gdal_error());
      m.in_transaction = true;
    }
  }
  CSLDestroy(layer_options);

  for (const auto& [name, type] :
       std::initializer_list<std::pair<const char*, OGRFieldType>>{{"nozzle", OFTInteger},
                                                                   {"utc_start", OFTString},
                                                                   {"utc_end", OFTString},
                                                                   {"rate_l_ha", OFTReal},
                                                                   {"volume_l", OFTReal},
                                                                   {"area_m2", OFTReal},
                                                                   {"duty_pct", OFTReal},
                                                                   {"weed_dens", OFTReal},
                                                                   {"crop_dens", OFTReal},
                                                                   {"speed_m_s", OFTReal}}) {
    add_field(m.sprayed.layer, name, type, m.sprayed.file);
  }
  if (board_field) add_field(m.sprayed.layer, "board", OFTString, m.sprayed.file);
  add_field(m.density.layer, "weed_dens", OFTReal, m.density.file);
  add_field(m.density.layer, "crop_dens", OFTReal, m.density.file);
  add_field(m.density.layer, "samples", OFTInteger64, m.density.file);
  for (Layer* l : {&m.sprayed, &m.density}) {
    l->feature.reset(OGRFeature::CreateFeature(l->layer->GetLayerDefn()));
  }
}

OgrMapWriter::~OgrMapWriter() = default;  // an unclosed export is rolled back / left partial

void OgrMapWriter::add(const Stretch& s, const std::string& board) {
  Impl& m = *impl_;
  OGRFeature& f = *m.sprayed.feature;
  f.SetField(0, static_cast<int>(s.nozzle));
  f.SetField(1, s.utc_start_ns != 0 ? format_utc_ms(s.utc_start_ns).c_str() : "");
  f.SetField(2, s.utc_end_ns != 0 ? format_utc_ms(s.utc_end_ns).c_str() : "");
  f.SetField(3, s.rate_l_per_ha());
  f.SetField(4, s.volume_l);
  f.SetField(5, s.area_m2);
  f.SetField(6, s.mean(s.duty_pct_s));
  f.SetField(7, s.mean(s.weed_density_s));
  f.SetField(8, s.mean(s.crop_density_s));
  f.SetField(9, s.mean(s.speed_m));
  if (m.board_field) f.SetField(10, board.c_str());
  m.ring.assign(s.left.begin(), s.left.end());
  m.ring.insert(m.ring.end(), s.right.rbegin(), s.right.rend());
  m.sprayed.write(polygon(m.ring));
}

void OgrMapWriter::add(const DensityCell& c) {
  Impl& m = *impl_;
  OGRFeature& f = *m.density.feature;
  f.SetField(0, c.weed_density);
  f.SetField(1, c.crop_density);
  f.SetField(2, static_cast<GIntBig>(c.samples));
  m.density.write(polygon({c.corners.begin(), c.corners.end()}));
}

void OgrMapWriter::close() {
  Impl& m = *impl_;
  if (m.in_transaction) {
    if (m.datasets.front()->CommitTransaction() != OGRERR_NONE)
      throw std::runtime_error(m.sprayed.file.string() + ": commit failed: " + gdal_error());
    m.in_transaction = false;
  }
  m.sprayed.feature.reset();
  m.density.feature.reset();
  for (Dataset& ds : m.datasets) {
    CPLErrorReset();
    GDALDataset* raw = ds.release();
    GDALClose(raw);
    if (CPLGetLastErrorType() >= CE_Failure)
      throw std::runtime_error(m.sprayed.file.string() + ": closing failed: " + gdal_error());
  }
  m.datasets.clear();
}

}  // namespace weedspray::daemon::maps
