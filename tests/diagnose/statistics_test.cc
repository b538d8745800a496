#include "libcalib/diagnose/statistics.h"

#include <gtest/gtest.h>

#include <Eigen/QR>

#include <random>

namespace rtscalib {
namespace {

// Table values of chi2 and normal quantiles (Abramowitz & Stegun 26.4, 26.2),
// given there to 3-4 decimals.
TEST(Statistics, ChiSquareSurvivalMatchesTables) {
  EXPECT_NEAR(ChiSquareSurvival(3.841, 1), 0.05, 1e-4);
  EXPECT_NEAR(ChiSquareSurvival(5.991, 2), 0.05, 1e-4);
  EXPECT_NEAR(ChiSquareSurvival(18.307, 10), 0.05, 1e-4);
  EXPECT_NEAR(ChiSquareSurvival(6.635, 1), 0.01, 1e-4);
  EXPECT_NEAR(ChiSquareSurvival(2.0, 2), std::exp(-1.0), 1e-12);  // chi2(2) is exponential
  EXPECT_DOUBLE_EQ(ChiSquareSurvival(0.0, 3), 1.0);
}

TEST(Statistics, CriticalValuesInvertTheSurvival) {
  EXPECT_NEAR(ChiSquareCritical(0.05, 1), 3.841, 1e-3);
  EXPECT_NEAR(ChiSquareCritical(1e-6, 3), 30.66, 1e-2);
  EXPECT_NEAR(NormalCritical(0.025), 1.960, 1e-3);
  EXPECT_NEAR(NormalCritical(0.0005), 3.291, 1e-3);  // Baarda's alpha0 = 0.001, two-sided
}

TEST(Statistics, ProjectorDropsDirectionsAlreadyInTheSpan) {
  Eigen::MatrixXd a = Eigen::MatrixXd::Random(50, 3);
  Projector p(50);
  EXPECT_EQ(p.Add(a), 3);
  Eigen::MatrixXd b(50, 2);
  b.col(0) = a.col(0) + 2 * a.col(1);  // in the span
  b.col(1) = Eigen::VectorXd::Random(50);
  EXPECT_EQ(p.Add(b), 1);
  EXPECT_LT(p.Apply(a).norm(), 1e-12);
  EXPECT_NEAR((p.basis().transpose() * p.basis() - Eigen::MatrixXd::Identity(4, 4)).norm(), 0,
              1e-12);
}

// Tall matrices (rows >= 4 columns) are factored block by block (TSQR): the
// projection must be the one of a single Householder QR of all rows, with
// row counts that leave a full last block, a short one merged into its
// predecessor, and one block only. Both are sums of products of unit
// columns: they agree to round-off (1e-11 on 5,000 rows, ~100 times double
// precision times sqrt(rows)).
TEST(Statistics, ProjectorOfTallMatricesIsTheOneOfASingleQr) {
  for (const int rows : {5000, 4924, 100, 60}) {
    const Eigen::MatrixXd a = Eigen::MatrixXd::Random(rows, 20);
    Eigen::MatrixXd with_dependent(rows, 21);
    with_dependent << a, a.col(3) - 0.5 * a.col(7);
    Projector p(rows);
    EXPECT_EQ(p.Add(with_dependent), 20) << rows;
    const Eigen::MatrixXd x = Eigen::MatrixXd::Random(rows, 5);
    const Eigen::HouseholderQR<Eigen::MatrixXd> qr(a);
    const Eigen::MatrixXd q = qr.householderQ() * Eigen::MatrixXd::Identity(rows, 20);
    const Eigen::MatrixXd expected = x - q * (q.transpose() * x);
    EXPECT_LT((p.Apply(x) - expected).norm(), 1e-11) << rows;
    EXPECT_NEAR((p.basis().transpose() * p.basis() - Eigen::MatrixXd::Identity(20, 20)).norm(), 0,
                1e-11)
        << rows;
  }
}

// What the probes' forward selection relies on: an x projected by a basis
// and then by the directions added to it since (Project(x, from)) is x
// projected by the whole basis at once. Both are sums of a few products of
// unit columns with O(1) entries: they agree to round-off (1e-12 here, about
// 100 times double precision on 200 rows).
TEST(Statistics, ProjectingByTheNewDirectionsKeepsAProjectionUpToDate) {
  const Eigen::MatrixXd x = Eigen::MatrixXd::Random(200, 6);
  Projector p(200);
  p.Add(Eigen::MatrixXd::Random(200, 4));
  Eigen::MatrixXd kept = p.Apply(x);
  const int known = p.rank();
  EXPECT_EQ(p.Add(Eigen::MatrixXd::Random(200, 3)), 3);
  p.Project(kept, known);
  EXPECT_LT((kept - p.Apply(x)).norm(), 1e-12);
  EXPECT_LT((p.basis().transpose() * kept).norm(), 1e-12);  // orthogonal to all 7
  // Nothing new: projecting from the end of the basis changes nothing.
  const Eigen::MatrixXd before = kept;
  p.Project(kept, p.rank());
  EXPECT_EQ(kept, before);
}

// A column with no relation to the data is significant at level a in about
// a of the trials; a real one always.
TEST(Statistics, TestColumnsHasItsLevelAndPower) {
  std::mt19937_64 rng(5);
  std::normal_distribution<double> n(0, 1);
  const int rows = 400, clusters = 100, trials = 400;
  std::vector<int> cluster(rows);
  for (int i = 0; i < rows; ++i) cluster[i] = i % clusters;
  int false_alarms = 0, hits = 0;
  for (int t = 0; t < trials; ++t) {
    Eigen::VectorXd y(rows);
    Eigen::MatrixXd x(rows, 2);
    for (int i = 0; i < rows; ++i) {
      y[i] = n(rng);
      x(i, 0) = n(rng);
      x(i, 1) = n(rng);
    }
    if (TestColumns(y, x, cluster, clusters, 0).p_value < 0.05) ++false_alarms;
    if (TestColumns(y + 0.3 * x.col(0), x, cluster, clusters, 0).p_value < 0.05) ++hits;
  }
  // Binomial(400, 0.05): mean 20, sd 4.4; the conservative (min) Wald may
  // fall below it but not far above.
  EXPECT_LE(false_alarms, 35);
  EXPECT_GE(hits, 390);
}

// Heteroscedastic noise that grows with the regressor: the classical test
// alone would reject far too often, the robust one keeps its level.
TEST(Statistics, HeteroscedasticNoiseDoesNotFakeSignificance) {
  std::mt19937_64 rng(9);
  std::normal_distribution<double> n(0, 1);
  const int rows = 600, trials = 300;
  std::vector<int> cluster(rows);
  for (int i = 0; i < rows; ++i) cluster[i] = i;
  int alarms = 0;
  for (int t = 0; t < trials; ++t) {
    Eigen::VectorXd y(rows);
    Eigen::MatrixXd x(rows, 1);
    for (int i = 0; i < rows; ++i) {
      const double d = i % 4 == 0 ? 20.0 : 1.0;  // like EDM distances 1 m and 20 m
      x(i, 0) = d * n(rng);
      y[i] = d * n(rng);
    }
    if (TestColumns(y, x, cluster, rows, 0).p_value < 0.01) ++alarms;
  }
  EXPECT_LE(alarms, 10);  // 3 expected
}

}  // namespace
}  // namespace rtscalib
