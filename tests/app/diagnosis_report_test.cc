// report.json's diagnosis (app/diagnosis_report.h): `diagnosis.unexplained`
// is SPEC 6's one list of what no catalogue effect explains, harmonics and
// structure findings (a drift against the record order among them) alike,
// each with SPEC 6's keys; `diagnosis.structure` keeps only the explained
// and negligible findings, so nothing unexplained is listed twice.
#include "app/diagnosis_report.h"

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

namespace rtscalib {
namespace {

using nlohmann::json;

CalibrationResult WithFindings() {
  CalibrationResult r;
  Diagnosis d;
  Harmonic h;
  h.probe.kind = ProbeKind::kHarmonic;
  h.probe.reading = Reading::kPhi;
  h.probe.variable = Reading::kPhi;
  h.probe.harmonic = 2;
  h.amplitude = 3.1;
  h.unit = "arcsec";
  h.significant = true;
  h.material = true;
  h.description = "twice per turn in phi";
  d.harmonics.unexplained.push_back(h);
  StructureFinding drift;
  drift.probe.kind = ProbeKind::kReadingTrend;
  drift.variable = "record order";
  drift.quantity = "phi (horizontal angle) error";
  drift.form = "a drift";
  drift.size = 20.2;
  drift.unit = "arcsec";
  drift.unexplained = true;
  drift.material = true;
  drift.description = "phi (horizontal angle) error drifts slowly with the record order";
  d.structure.unexplained.push_back(drift);
  StructureFinding field = drift;
  field.probe.kind = ProbeKind::kImageField;
  field.probe.zoom = 0;
  field.variable = "image position";
  field.size = 0.4;
  field.unit = "px";
  d.structure.unexplained.push_back(field);
  StructureFinding explained = drift;
  explained.variable = "target distance";
  explained.unexplained = false;
  explained.explained_by = "edm_scale";
  d.structure.explained.push_back(explained);
  r.diagnosis = d;
  return r;
}

TEST(DiagnosisJson, UnexplainedIsOneListOfHarmonicsAndStructure) {
  const json j = app::DiagnosisJson(WithFindings());
  const json& u = j.at("unexplained");
  ASSERT_EQ(u.size(), 3u) << u.dump(1);
  // SPEC 6's keys on every entry.
  for (const json& e : u) {
    for (const char* key : {"variable", "harmonic", "amplitude", "significant", "kind"}) {
      EXPECT_TRUE(e.contains(key)) << key << " in " << e.dump();
    }
    EXPECT_EQ(e.at("significant"), true) << e.dump();
  }
  EXPECT_EQ(u[0].at("kind"), "harmonic");
  EXPECT_EQ(u[0].at("variable"), "phi");
  EXPECT_EQ(u[0].at("harmonic"), 2);
  EXPECT_DOUBLE_EQ(u[0].at("amplitude").get<double>(), 3.1);
  EXPECT_EQ(u[1].at("kind"), "reading_trend");
  EXPECT_EQ(u[1].at("variable"), "record order");
  EXPECT_EQ(u[1].at("harmonic"), 0);
  EXPECT_DOUBLE_EQ(u[1].at("amplitude").get<double>(), 20.2);
  EXPECT_EQ(u[1].at("unit"), "arcsec");
  EXPECT_EQ(u[2].at("kind"), "image_field");
  EXPECT_EQ(u[2].at("variable"), "image position");
  EXPECT_EQ(u[2].at("zoom"), 0);
  // The structure object lists the rest, and no second unexplained list.
  const json& s = j.at("structure");
  EXPECT_FALSE(s.contains("unexplained")) << s.dump(1);
  ASSERT_EQ(s.at("explained").size(), 1u);
  EXPECT_EQ(s.at("explained")[0].at("explained_by"), "edm_scale");
  EXPECT_TRUE(s.at("negligible").empty());
}

TEST(DiagnosisJson, NothingUnexplainedIsAnEmptyList) {
  CalibrationResult r;
  r.diagnosis = Diagnosis();
  const json j = app::DiagnosisJson(r);
  ASSERT_TRUE(j.at("unexplained").is_array());
  EXPECT_TRUE(j.at("unexplained").empty());
}

}  // namespace
}  // namespace rtscalib
