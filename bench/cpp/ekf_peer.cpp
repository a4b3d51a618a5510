// A C++17 / Eigen 3 peer of leakwatch's 7-state thesis filter (issue 32),
// built and run by bench/cpp/compare.sh (docs/performance.md, "The C++ peer").
//
// The same model as model/src/process{,/rhs.rs,/discrete.rs} for 7 states on
// the thesis rig's default parameters (model/src/params.rs), the same tuning
// (filter/src/tuning.rs, Tuning::thesis) and the same per-sample sequence as
// filter/src/lib.rs (Estimator::on_sample): the thesis start, the command of
// the previous sample over each interval, one forward-Euler step with the
// analytic Jacobian, the clamps after the prediction and after the update,
// all three channels measured (H selects x, p1, p2). The covariance is carried
// in leakwatch's scaled units (z = x / scale, filter/src/lib.rs SCALE).
//
// Variants (all fixed-size Eigen matrices):
//   joseph     covariance form: P⁻ = F P Fᵀ + Q (dense), dense H (3×7 of 0/1),
//              the Joseph update P⁺ = (I − K H) P (I − K H)ᵀ + K R Kᵀ,
//              P⁺ symmetrised
//   joseph8    the same, every matrix padded to 8 states (the 8th a dummy
//              that stays zero), so a column fills a vector register
//   selector   the joseph update with H applied as a selector: H P is three rows of P,
//              P Hᵀ three columns, I − K H the identity but in three columns
//              (A P = P − K (H P), A P Aᵀ = A P − (A P Hᵀ) Kᵀ, the measured
//              rows and columns through the 3×3 block I − H K)
//   sqrt       leakwatch's own algorithm (filter/src/ekf.rs): a factor S with
//              P = S Sᵀ, predict by the sparse product F S and the Cholesky
//              factor of W Wᵀ + Q, update by Potter's scalar updates
//
// Usage:
//   ekf_peer --csv SAMPLES.csv [--steps N] [--rounds R] [--json OUT.json]
//            [--compare ESTIMATES.csv [--agree-from SECONDS]]
//            [--leakwatch PATH [--bench-dir DIR]] [--leakwatch-json EKF.json]...
//            [--variants joseph,joseph8,selector,sqrt] [--dump PREFIX]
// SAMPLES.csv is `leakwatch simulate`'s CSV (t,u,x,p1,p2,...); every row
// must have all channels usable. --compare reads the th_* columns of
// `leakwatch replay SAMPLES.csv --model 7`'s estimates.csv and prints how far
// each variant's estimates are from them, over the whole stream and from
// --agree-from seconds on (default 0.5: the thesis' P0 = 1e4·I makes the
// first steps' algebra ill-conditioned, so both sides' rounding differs
// there until the filter has forgotten its start). --leakwatch runs
// `PATH bench ekf --steps N --out DIR/round-K` after each round of the C++
// variants (so both sides see the same load) and prints one table of both
// sides' medians over rounds and their ratio to the C++ Joseph peer;
// --leakwatch-json adds an ekf.json measured before as one more round.
// --dump writes every estimate of each variant to PREFIX.VARIANT.csv.
// Timing: every predict + update (model step, clamps and NIS included) timed
// on its own with the monotonic clock (std::chrono::steady_clock), the stream
// looped (the filter restarted at its end, as `bench ekf` does) until N steps
// (default 1e6); R rounds per variant (default 3), interleaved; the figures
// are the median over rounds of each round's median (p99 likewise).

#include <Eigen/Dense>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace {

constexpr int N = 7;
constexpr int M = 3;
using Vec = Eigen::Matrix<double, N, 1>;
using Mat = Eigen::Matrix<double, N, N>;
using MatMN = Eigen::Matrix<double, M, N>;
using MatNM = Eigen::Matrix<double, N, M>;
using VecM = Eigen::Matrix<double, M, 1>;
using MatM = Eigen::Matrix<double, M, M>;
// The covariance padded to 8 states (the 8th a dummy that stays zero): a column
// fills one AVX-512 register (four AVX2 ones), where Eigen leaves 7×7 products scalar.
using Mat8 = Eigen::Matrix<double, 8, 8>;
using Vec8 = Eigen::Matrix<double, 8, 1>;
using Mat38 = Eigen::Matrix<double, M, 8>;
using Mat83 = Eigen::Matrix<double, 8, M>;
using MatR = Eigen::Matrix<double, N, N, Eigen::RowMajor>;  // rows contiguous (the square-root form's S and W)

// ---------------------------------------------------------------- parameters
// model/src/params.rs, ActuatorParams::default() (the thesis rig), with what
// the 7-state layout leaves out at its neutral value: double-rod (A2 = A1),
// horizontal (no gravity), no entrained air, no supply sag (the thesis layouts
// drop it, filter/src/lib.rs), no valve null leakage, no built-in leaks, no end
// stops (6/7 states have none), no spool bias state.
struct Params {
    double area_m2 = 6.33e-4;
    double mass_kg = 10.0;
    double x_min_m = 0.0;
    double x_max_m = 0.6069;
    double dead_volume_1_m3 = 2.14e-5;
    double dead_volume_2_m3 = 2.14e-5;
    double bulk_modulus_pa = 6.89e8;
    double oil_density_kg_m3 = 847.15;
    double discharge_coefficient = 0.6;
    double area_gradient_m2_per_m = 2.075e-2;
    double spool_gain_m_per_v = 2.794e-5;
    double spool_natural_freq_rad_s = 200.0 * 3.14159265358979323846;
    double spool_damping_ratio = 0.7;
    double spool_null_bias_m = 0.0;
    double supply_pressure_pa = 13.8e6;
    double return_pressure_pa = 0.0;
};

// filter/src/tuning.rs, Tuning::thesis(): 7 states, T = 1 ms, 1 Euler step.
struct Tuning {
    double dt_s = 1e-3;
    double init_pressure_pa = 6.8e6;
    double q[N] = {1e-10, 1e4, 1e4, 1e-6, 1e-4, 1e-20, 1e2};
    double r[M] = {1e-4, 1e6, 1e6};
    double p0[N] = {1e4, 1e4, 1e4, 1e4, 1e4, 1e4, 1e4};
};

// filter/src/lib.rs SCALE: each state's typical magnitude (the covariance's unit).
constexpr double SCALE[N] = {1e-5, 1e6, 1e6, 1e-3, 1e-2, 1e-2, 1e2};
// The measurement y = [x, p1, p2] reads these states (model MEASURED_STATES).
constexpr int SEL[M] = {3, 1, 2};
// model/src/process.rs MIN_SLOPE_DROP_PA.
constexpr double MIN_SLOPE_DROP_PA = 1.0e3;

inline double signed_sqrt(double v) { return v >= 0.0 ? std::sqrt(v) : -std::sqrt(-v); }
inline double sqrt_slope(double dp) { return 0.5 / std::sqrt(std::max(std::abs(dp), MIN_SLOPE_DROP_PA)); }

// ---------------------------------------------------------------- the model
struct Model {
    Params p;
    double dt_s;
    double p_min_pa;  // ProcessModel::new: -1e5
    double p_max_pa;  // 1.5 p_s

    explicit Model(const Params& params, double dt) : p(params), dt_s(dt), p_min_pa(-1.0e5), p_max_pa(1.5 * params.supply_pressure_pa) {}

    double nominal_chamber_pressure_pa() const { return 0.5 * (p.supply_pressure_pa + p.return_pressure_pa); }

    // rhs.rs ProcessModel::linearise for N = 7: f(x, u) and A = ∂f/∂x.
    // (J: the 7×7 Jacobian, or an 8×8 whose last row and column stay zero.)
    template <class J>
    void linearise(const Vec& s, double u_v, Vec& f, J& a) const {
        const double x_sp = s[0], p1 = s[1], p2 = s[2], x = s[3], v = s[4], v_sp = s[5];
        f.setZero();
        a.setZero();
        // spool: second order
        const double wn = p.spool_natural_freq_rad_s;
        f[0] = v_sp;
        a(0, 5) = 1.0;
        const double bias = p.spool_null_bias_m;
        f[5] = -2.0 * p.spool_damping_ratio * wn * v_sp - wn * wn * (x_sp - bias) + p.spool_gain_m_per_v * wn * wn * u_v;
        a(5, 0) = -wn * wn;
        a(5, 5) = -2.0 * p.spool_damping_ratio * wn;

        // valve (dynamics.rs orifice_flows / land_flow, no sag) and its partials (orifice_partials)
        const double ps = p.supply_pressure_pa, pr = p.return_pressure_pa;
        const double w = p.area_gradient_m2_per_m;
        const double root = std::sqrt(2.0 / p.oil_density_kg_m3);
        const double g = p.discharge_coefficient * w * root;
        double q1, q2, dq1x, dq1p1, dq2x, dq2p2;
        if (x_sp >= 0.0) {
            q1 = p.discharge_coefficient * w * x_sp * root * signed_sqrt(ps - p1);
            q2 = p.discharge_coefficient * w * x_sp * root * signed_sqrt(p2 - pr);
            dq1x = g * signed_sqrt(ps - p1);
            dq1p1 = -g * x_sp * sqrt_slope(ps - p1);
            dq2x = g * signed_sqrt(p2 - pr);
            dq2p2 = g * x_sp * sqrt_slope(p2 - pr);
        } else {
            q1 = -(p.discharge_coefficient * w * -x_sp * root * signed_sqrt(p1 - pr));
            q2 = -(p.discharge_coefficient * w * -x_sp * root * signed_sqrt(ps - p2));
            dq1x = g * signed_sqrt(p1 - pr);
            dq1p1 = g * x_sp * sqrt_slope(p1 - pr);
            dq2x = g * signed_sqrt(ps - p2);
            dq2p2 = -g * x_sp * sqrt_slope(ps - p2);
        }

        // chambers (params.rs chamber_volumes_m3)
        const double a1 = p.area_m2, a2 = p.area_m2;
        const double v1 = std::max(p.dead_volume_1_m3 + a1 * (x - p.x_min_m), 0.01 * p.dead_volume_1_m3);
        const double v2 = std::max(p.dead_volume_2_m3 + a2 * (p.x_max_m - x), 0.01 * p.dead_volume_2_m3);
        const double b1 = p.bulk_modulus_pa, b2 = p.bulk_modulus_pa;
        const double net1 = q1 - a1 * v;
        const double net2 = a2 * v - q2;
        f[1] = b1 / v1 * net1;
        f[2] = b2 / v2 * net2;
        a(1, 0) = b1 / v1 * dq1x;
        a(1, 1) = b1 / v1 * dq1p1;
        a(2, 0) = -b2 / v2 * dq2x;
        a(2, 2) = b2 / v2 * -dq2p2;
        a(1, 3) = -b1 * net1 * a1 / (v1 * v1);
        a(2, 3) = b2 * net2 * a2 / (v2 * v2);
        a(1, 4) = -b1 / v1 * a1;
        a(2, 4) = b2 / v2 * a2;

        // rod: the effective load F_e takes friction and environment
        f[3] = v;
        a(3, 4) = 1.0;
        const double m = p.mass_kg;
        f[4] = (p.area_m2 * (p1 - p2) - s[6]) / m;
        a(4, 1) = a1 / m;
        a(4, 2) = -a2 / m;
        a(4, 6) = -1.0 / m;
    }

    // discrete.rs ProcessModel::keep_physical (7 states): pressures and rod position.
    void keep_physical(Vec& x) const {
        for (int i : {1, 2}) {
            if (!std::isfinite(x[i]))
                x[i] = nominal_chamber_pressure_pa();
            else
                x[i] = std::clamp(x[i], p_min_pa, p_max_pa);
        }
        x[3] = std::clamp(x[3], p.x_min_m - 0.01, p.x_max_m + 0.01);
    }

    // discrete.rs ProcessModel::step, one Euler step: x(k+1) = x + T f, F = I + T A.
    template <class J>
    void step(const Vec& s, double u_v, Vec& x, J& jac) const {
        Vec f;
        linearise(s, u_v, f, jac);
        x = s + f * dt_s;
        jac *= dt_s;
        jac.diagonal().array() += 1.0;
        keep_physical(x);
    }
};

// ---------------------------------------------------------------- samples
struct Sample {
    double t, u, x, p1, p2;
};

std::vector<std::string> split(const std::string& line) {
    std::vector<std::string> out;
    std::stringstream ss(line);
    std::string cell;
    while (std::getline(ss, cell, ',')) out.push_back(cell);
    return out;
}

int column(const std::vector<std::string>& header, const std::string& name, const std::string& file) {
    for (size_t i = 0; i < header.size(); ++i)
        if (header[i] == name) return static_cast<int>(i);
    std::fprintf(stderr, "ekf_peer: %s has no column %s\n", file.c_str(), name.c_str());
    std::exit(2);
}

// A table of named columns (doubles; "NaN" and empty cells read as NaN).
std::vector<std::vector<double>> read_columns(const std::string& file, const std::vector<std::string>& names) {
    std::ifstream in(file);
    if (!in) {
        std::fprintf(stderr, "ekf_peer: cannot read %s\n", file.c_str());
        std::exit(2);
    }
    std::string line;
    std::getline(in, line);
    const auto header = split(line);
    std::vector<int> idx;
    for (const auto& n : names) idx.push_back(column(header, n, file));
    std::vector<std::vector<double>> cols(names.size());
    while (std::getline(in, line)) {
        if (line.empty()) continue;
        const auto cells = split(line);
        for (size_t k = 0; k < idx.size(); ++k) {
            const auto i = static_cast<size_t>(idx[k]);
            cols[k].push_back(i < cells.size() && !cells[i].empty() ? std::strtod(cells[i].c_str(), nullptr) : NAN);
        }
    }
    return cols;
}

// ---------------------------------------------------------------- filters
enum class Variant { Joseph, Joseph8, Selector, Sqrt };
const char* variant_name(Variant v) {
    switch (v) {
        case Variant::Joseph: return "joseph";
        case Variant::Joseph8: return "joseph8";
        case Variant::Selector: return "selector";
        default: return "sqrt";
    }
}
const char* variant_label(Variant v) {
    switch (v) {
        case Variant::Joseph: return "C++/Eigen, covariance form, Joseph update (dense H)";
        case Variant::Joseph8: return "C++/Eigen, the same padded to 8×8";
        case Variant::Selector: return "C++/Eigen, Joseph update with H as a selector";
        default: return "C++/Eigen, leakwatch's algorithm (factor S, Cholesky predict, Potter updates)";
    }
}

struct Filter {
    const Model* model;
    Vec x;         // state, SI
    Mat P;         // covariance, scaled (Joseph variants)
    MatR S;        // factor P = S Sᵀ, scaled (sqrt variant), lower triangular after a predict
    Mat ratio;     // scale[j] / scale[i]
    Vec qz;        // Q, scaled
    Vec qz_sqrt;   // √Q, scaled
    VecM rz;       // R, scaled to the measured states' units
    VecM r;        // R, SI (sqrt variant: measurement units, as ekf.rs)
    MatMN H;       // dense selector, scaled units
    Mat8 P8;       // joseph8: P padded with a zero 8th row and column
    Mat8 ratio8;   // ratio padded with zeros
    Vec8 qz8;      // Q padded with a zero
    Mat38 H8;      // H padded with a zero column
    Vec scale;
    double nis = 0.0;

    Filter(const Model& m, const Tuning& t) : model(&m) {
        for (int i = 0; i < N; ++i) scale[i] = SCALE[i];
        for (int i = 0; i < N; ++i)
            for (int j = 0; j < N; ++j) ratio(i, j) = SCALE[j] / SCALE[i];
        for (int i = 0; i < N; ++i) {
            qz_sqrt[i] = std::sqrt(std::max(t.q[i], 0.0)) / SCALE[i];
            qz[i] = qz_sqrt[i] * qz_sqrt[i];
        }
        ratio8.setZero();
        ratio8.topLeftCorner<N, N>() = ratio;
        qz8.setZero();
        qz8.head<N>() = qz;
        H8.setZero();
        H.setZero();
        for (int k = 0; k < M; ++k) {
            H8(k, SEL[k]) = 1.0;
            H(k, SEL[k]) = 1.0;
            rz[k] = t.r[k] / (SCALE[SEL[k]] * SCALE[SEL[k]]);
            r[k] = t.r[k];
        }
        reset(t);
    }

    // Init::Thesis: zeros, both pressures at init_pressure_pa, P0 diagonal.
    void reset(const Tuning& t) {
        x.setZero();
        x[1] = t.init_pressure_pa;
        x[2] = t.init_pressure_pa;
        P.setZero();
        S.setZero();
        for (int i = 0; i < N; ++i) {
            const double d = std::sqrt(std::max(t.p0[i], 0.0)) / SCALE[i];
            S(i, i) = d;
            P(i, i) = d * d;
        }
        P8.setZero();
        P8.topLeftCorner<N, N>() = P;
    }

    VecM innovation_scaled(const VecM& y) const {
        VecM nu;
        for (int k = 0; k < M; ++k) nu[k] = (y[k] - x[SEL[k]]) / SCALE[SEL[k]];
        return nu;
    }

    // ---- covariance form
    // P ← (P + Pᵀ)/2: rounding leaves the products' two triangles apart.
    void symmetrise() {
        const Mat Pt = P.transpose();
        P = 0.5 * (P + Pt);
    }

    void predict_cov(const Vec& x_pred, const Mat& F) {
        const Mat Fz = F.cwiseProduct(ratio);
        const Mat tmp = Fz.lazyProduct(P);
        P = tmp.lazyProduct(Fz.transpose());
        P.diagonal() += qz;
        x = x_pred;
    }

    void update_joseph(const VecM& y) {
        const VecM nu = innovation_scaled(y);
        MatNM PHt;
        PHt.noalias() = P * H.transpose();
        MatM C;
        C.noalias() = H * PHt;
        C.diagonal() += rz;
        const MatM Ci = C.inverse();
        MatNM K;
        K.noalias() = PHt * Ci;
        nis = nu.dot(Ci * nu);
        x += (K * nu).cwiseProduct(scale);
        Mat A = Mat::Identity();
        A.noalias() -= K * H;
        const Mat AP = A.lazyProduct(P);
        P = AP.lazyProduct(A.transpose());
        P.noalias() += (K * rz.asDiagonal()).lazyProduct(K.transpose());
        symmetrise();
        model->keep_physical(x);
    }

    // ---- the covariance form padded to 8×8 (the same algebra as predict_cov, update_joseph)
    void predict_cov8(const Vec& x_pred, const Mat8& F) {
        const Mat8 Fz = F.cwiseProduct(ratio8);
        const Mat8 tmp = Fz.lazyProduct(P8);
        P8 = tmp.lazyProduct(Fz.transpose());
        P8.diagonal() += qz8;
        x = x_pred;
    }

    void update_joseph8(const VecM& y) {
        const VecM nu = innovation_scaled(y);
        Mat83 PHt;
        PHt.noalias() = P8 * H8.transpose();
        MatM C;
        C.noalias() = H8 * PHt;
        C.diagonal() += rz;
        const MatM Ci = C.inverse();
        Mat83 K;
        K.noalias() = PHt * Ci;
        nis = nu.dot(Ci * nu);
        const Vec8 dz = K * nu;
        x += dz.head<N>().cwiseProduct(scale);
        Mat8 A = Mat8::Identity();
        A.noalias() -= K * H8;
        const Mat8 AP = A.lazyProduct(P8);
        P8 = AP.lazyProduct(A.transpose());
        P8.noalias() += (K * rz.asDiagonal()).lazyProduct(K.transpose());
        const Mat8 Pt = P8.transpose();
        P8 = 0.5 * (P8 + Pt);
        model->keep_physical(x);
    }

    void update_selector(const VecM& y) {
        const VecM nu = innovation_scaled(y);
        MatMN HP;  // H P: the measured states' rows of P
        for (int k = 0; k < M; ++k) HP.row(k) = P.row(SEL[k]);
        MatM C;  // H P Hᵀ + R
        for (int k = 0; k < M; ++k)
            for (int l = 0; l < M; ++l) C(k, l) = HP(k, SEL[l]);
        C.diagonal() += rz;
        const MatM Ci = C.inverse();
        MatNM K;
        K.noalias() = HP.transpose() * Ci;
        nis = nu.dot(Ci * nu);
        x += (K * nu).cwiseProduct(scale);
        // A = I − K H is the identity but in the measured states' columns; its
        // 3×3 block there, I − H K, is formed first (a gain near 1 leaves a
        // small 1 − k, exact), as a dense A has it.
        MatM Ah = MatM::Identity();
        for (int k = 0; k < M; ++k) Ah.row(k) -= K.row(SEL[k]);
        // A P = P − K (H P), and its measured rows (I − H K) H P
        Mat AP = P;
        AP.noalias() -= K.lazyProduct(HP);
        const MatMN AhHP = Ah.lazyProduct(HP);
        for (int k = 0; k < M; ++k) AP.row(SEL[k]) = AhHP.row(k);
        // A P Aᵀ = A P − (A P Hᵀ) Kᵀ, and its measured columns (A P Hᵀ)(I − H K)ᵀ
        MatNM APHt;
        for (int k = 0; k < M; ++k) APHt.col(k) = AP.col(SEL[k]);
        P = AP;
        P.noalias() -= APHt.lazyProduct(K.transpose());
        const MatNM APAtHt = APHt.lazyProduct(Ah.transpose());
        for (int k = 0; k < M; ++k) P.col(SEL[k]) = APAtHt.col(k);
        // + K R Kᵀ
        P.noalias() += (K * rz.asDiagonal()).lazyProduct(K.transpose());
        symmetrise();
        model->keep_physical(x);
    }

    // ---- leakwatch's square-root algorithm (filter/src/ekf.rs)
    static bool cholesky_lower(MatR& a) {
        for (int j = 0; j < N; ++j) {
            const double d = a(j, j);
            if (!(d > 0.0 && std::isfinite(d))) return false;
            const double ljj = std::sqrt(d);
            a(j, j) = ljj;
            const double inv = 1.0 / ljj;
            for (int i = j + 1; i < N; ++i) a(i, j) *= inv;
            for (int c = j + 1; c < N; ++c)
                for (int i = c; i < N; ++i) a(i, c) -= a(i, j) * a(c, j);
        }
        return true;
    }

    static void lower_triangularise(MatR& w1, MatR& w2) {
        for (int i = 0; i < N; ++i) {
            double norm2 = 0.0;
            for (int j = i; j < N; ++j) norm2 += w1(i, j) * w1(i, j);
            for (int j = 0; j < N; ++j) norm2 += w2(i, j) * w2(i, j);
            const double norm = std::sqrt(norm2);
            if (norm == 0.0) continue;
            const double x0 = w1(i, i);
            const double alpha = x0 > 0.0 ? -norm : norm;
            const double v0 = x0 - alpha;
            const double vtv = 2.0 * (norm2 - alpha * x0);
            if (vtv == 0.0) continue;
            for (int r = i + 1; r < N; ++r) {
                double d = w1(r, i) * v0;
                for (int j = i + 1; j < N; ++j) d += w1(r, j) * w1(i, j);
                for (int j = 0; j < N; ++j) d += w2(r, j) * w2(i, j);
                const double gg = 2.0 * d / vtv;
                w1(r, i) -= gg * v0;
                for (int j = i + 1; j < N; ++j) w1(r, j) -= gg * w1(i, j);
                for (int j = 0; j < N; ++j) w2(r, j) -= gg * w2(i, j);
            }
            w1(i, i) = alpha;
            for (int j = i + 1; j < N; ++j) w1(i, j) = 0.0;
            for (int j = 0; j < N; ++j) w2(i, j) = 0.0;
        }
    }

    void predict_sqrt(const Vec& x_pred, const Mat& F) {
        // W = F_z S, F sparse: each non-zero adds a multiple of a row of S
        MatR W = MatR::Zero();
        for (int j = 0; j < N; ++j)
            for (int i = 0; i < N; ++i) {
                const double fij = F(i, j);
                if (fij != 0.0) W.row(i) += (fij * ratio(i, j)) * S.row(j);
            }
        MatR Pm;  // P⁻ = W Wᵀ + Q, its lower triangle (rows of W dotted)
        for (int i = 0; i < N; ++i)
            for (int j = 0; j <= i; ++j) Pm(i, j) = W.row(i).dot(W.row(j));
        Pm.diagonal() += qz;
        if (cholesky_lower(Pm)) {
            S = Pm.template triangularView<Eigen::Lower>();
        } else {
            MatR w2 = qz_sqrt.asDiagonal();
            lower_triangularise(W, w2);
            S = W;
        }
        x = x_pred;
    }

    void update_potter(const VecM& y) {
        VecM nu;
        for (int k = 0; k < M; ++k) nu[k] = y[k] - x[SEL[k]];
        // innovation statistics: C = H_z S Sᵀ H_zᵀ + R (measurement units), NIS
        MatM C;
        for (int i = 0; i < M; ++i)
            for (int j = 0; j <= i; ++j) {
                C(i, j) = SCALE[SEL[i]] * SCALE[SEL[j]] * S.row(SEL[i]).dot(S.row(SEL[j]));
                C(j, i) = C(i, j);
            }
        C.diagonal() += r;
        const Eigen::LLT<MatM> llt(C);
        nis = llt.matrixL().solve(nu).squaredNorm();
        Vec dz = Vec::Zero();
        for (int i = 0; i < M; ++i) {
            const int si = SEL[i];
            const double ci = SCALE[si];
            const Vec phi = ci * S.row(si).transpose();
            const double denom = phi.dot(phi) + r[i];
            const double a = 1.0 / denom;
            const double gamma = 1.0 / (1.0 + std::sqrt(a * r[i]));
            const Vec k = a * (S * phi);
            const double resid = nu[i] - ci * dz[si];
            dz += resid * k;
            S.noalias() -= (gamma * k) * phi.transpose();
        }
        x += dz.cwiseProduct(scale);
        model->keep_physical(x);
    }
};

// Keeps the compiler from moving or dropping work across the clock reads.
template <class T>
inline void escape(T const& v) {
    asm volatile("" : : "g"(&v) : "memory");
}

struct Runner {
    const Model& model;
    const Tuning& tuning;
    const std::vector<Sample>& samples;

    // One step of sample k (k = 0 starts the filter): predict with the command of
    // the previous sample (the first: its own), then update with all three channels.
    static inline void step(Filter& f, Variant v, const Model& model, double u, const VecM& y) {
        Vec xp;
        if (v == Variant::Joseph8) {
            Mat8 F8;
            model.step(f.x, u, xp, F8);
            f.predict_cov8(xp, F8);
            f.update_joseph8(y);
            return;
        }
        Mat F;
        model.step(f.x, u, xp, F);
        if (v == Variant::Sqrt) {
            f.predict_sqrt(xp, F);
            f.update_potter(y);
        } else {
            f.predict_cov(xp, F);
            if (v == Variant::Joseph)
                f.update_joseph(y);
            else
                f.update_selector(y);
        }
    }

    // Estimates of every sample (x, p1, p2, v, F_e, NIS), one untimed pass;
    // `indefinite` counts the samples after whose update the covariance is not
    // positive definite (its Cholesky factorisation fails; the square-root
    // form's P = S Sᵀ cannot be indefinite).
    std::vector<std::array<double, 6>> estimates(Variant v, size_t* indefinite = nullptr) const {
        std::vector<std::array<double, 6>> out;
        out.reserve(samples.size());
        Filter f(model, tuning);
        if (indefinite) *indefinite = 0;
        double last_u = samples.empty() ? 0.0 : samples[0].u;
        for (size_t k = 0; k < samples.size(); ++k) {
            const Sample& s = samples[k];
            const double u = k == 0 ? s.u : last_u;
            last_u = s.u;
            step(f, v, model, u, VecM(s.x, s.p1, s.p2));
            out.push_back({f.x[3], f.x[1], f.x[2], f.x[4], f.x[6], f.nis});
            const Mat P = v == Variant::Joseph8 ? Mat(f.P8.topLeftCorner<N, N>()) : f.P;
            if (indefinite && v != Variant::Sqrt && Eigen::LLT<Mat>(P).info() != Eigen::Success) ++*indefinite;
        }
        return out;
    }

    // Per-step times (ns) of at least `steps` steps.
    std::vector<double> time_steps(Variant v, uint64_t steps) const {
        std::vector<double> ns;
        ns.reserve(steps + samples.size());
        double sink = 0.0;
        while (ns.size() < steps) {
            Filter f(model, tuning);
            double last_u = samples[0].u;
            for (size_t k = 0; k < samples.size(); ++k) {
                const Sample& s = samples[k];
                const double u = k == 0 ? s.u : last_u;
                last_u = s.u;
                const VecM y(s.x, s.p1, s.p2);
                escape(y);
                const auto t0 = std::chrono::steady_clock::now();
                step(f, v, model, u, y);
                escape(f);
                const auto t1 = std::chrono::steady_clock::now();
                sink += f.nis;
                ns.push_back(static_cast<double>(std::chrono::duration_cast<std::chrono::nanoseconds>(t1 - t0).count()));
            }
        }
        escape(sink);
        return ns;
    }
};

double quantile_sorted(const std::vector<double>& v, double q) {
    if (v.empty()) return NAN;
    return v[static_cast<size_t>(std::llround((static_cast<double>(v.size()) - 1.0) * q))];
}

double median(std::vector<double> v) {
    std::sort(v.begin(), v.end());
    if (v.empty()) return NAN;
    const size_t n = v.size();
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

double timer_overhead_ns(int n) {
    std::vector<double> d(n);
    for (int i = 0; i < n; ++i) {
        const auto t0 = std::chrono::steady_clock::now();
        escape(t0);
        const auto t1 = std::chrono::steady_clock::now();
        d[i] = static_cast<double>(std::chrono::duration_cast<std::chrono::nanoseconds>(t1 - t0).count());
    }
    std::sort(d.begin(), d.end());
    return quantile_sorted(d, 0.5);
}

// How far a variant's estimates are from leakwatch's, from sample `from` on:
// per column, the largest |difference| over the largest |leakwatch's value|.
struct Agreement {
    double rel[6] = {0, 0, 0, 0, 0, 0};
    size_t worst_at[6] = {0, 0, 0, 0, 0, 0};
    double worst() const { return *std::max_element(rel, rel + 5); }  // the five states
};

const char* COLS[6] = {"th_x", "th_p1", "th_p2", "th_v", "th_f_e", "th_nis"};

Agreement compare(const std::vector<std::array<double, 6>>& mine, const std::vector<std::vector<double>>& ref, size_t from) {
    Agreement a;
    const size_t n = std::min(mine.size(), ref[0].size());
    for (int c = 0; c < 6; ++c) {
        double max_abs = 0.0, ref_max = 0.0;
        for (size_t k = from; k < n; ++k) {
            const double r = ref[c][k];
            const double d = std::abs(mine[k][c] - r);
            ref_max = std::max(ref_max, std::abs(r));
            if (!(d <= max_abs)) {  // NaN counts as the worst
                max_abs = d;
                a.worst_at[c] = k;
            }
        }
        a.rel[c] = max_abs / ref_max;
    }
    return a;
}

// The step-time rows of `leakwatch bench ekf --out DIR`'s ekf.json ("step_time":
// objects with "filter", "states", "median_ns", "p99_ns"), read by a plain scan
// so the peer needs no JSON library.
struct RustRow {
    std::string filter;
    int states = 0;
    double median_ns = NAN, p99_ns = NAN, timer_overhead_ns = NAN;
};

std::vector<RustRow> read_rust_json(const std::string& file) {
    std::ifstream in(file);
    std::stringstream ss;
    ss << in.rdbuf();
    const std::string text = ss.str();
    std::vector<RustRow> rows;
    size_t pos = text.find("\"step_time\"");
    if (pos == std::string::npos) return rows;
    const size_t end = text.find(']', pos);
    auto number = [&](size_t from, size_t to, const std::string& key) -> double {
        const size_t k = text.find("\"" + key + "\"", from);
        if (k == std::string::npos || k > to) return NAN;
        const size_t colon = text.find(':', k);
        return std::strtod(text.c_str() + colon + 1, nullptr);
    };
    while ((pos = text.find('{', pos)) != std::string::npos && pos < end) {
        const size_t close = text.find('}', pos);
        RustRow r;
        const size_t f = text.find("\"filter\"", pos);
        if (f != std::string::npos && f < close) {
            const size_t q0 = text.find('"', text.find(':', f)) + 1;
            r.filter = text.substr(q0, text.find('"', q0) - q0);
        }
        r.states = static_cast<int>(number(pos, close, "states"));
        r.median_ns = number(pos, close, "median_ns");
        r.p99_ns = number(pos, close, "p99_ns");
        r.timer_overhead_ns = number(pos, close, "timer_overhead_ns");
        rows.push_back(r);
        pos = close;
    }
    return rows;
}

// `s` as one word for /bin/sh.
std::string shell_quote(const std::string& s) {
    std::string out = "'";
    for (const char c : s) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
    return out + "'";
}

std::string json_string(const std::string& s) {
    std::string out = "\"";
    for (const char c : s) {
        if (c == '"' || c == '\\') out += '\\';
        out += c;
    }
    return out + "\"";
}

void usage() {
    std::fprintf(stderr,
                 "usage: ekf_peer --csv SAMPLES.csv [--steps N] [--rounds R] [--json OUT.json] "
                 "[--compare LEAKWATCH_ESTIMATES.csv [--agree-from SECONDS]] [--variants joseph,joseph8,selector,sqrt] "
                 "[--dump PREFIX] [--leakwatch PATH [--bench-dir DIR]] [--leakwatch-json EKF.json]...\n");
    std::exit(2);
}

}  // namespace

int main(int argc, char** argv) {
    std::string csv, json_out, compare_file, dump_prefix, leakwatch_bin, bench_dir = ".", variants_arg = "joseph,joseph8,selector,sqrt";
    std::vector<std::string> rust_jsons;
    uint64_t steps = 1000000;
    int rounds = 3;
    double agree_from_s = 0.5;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        auto next = [&]() -> std::string {
            if (i + 1 >= argc) usage();
            return argv[++i];
        };
        if (a == "--csv") csv = next();
        else if (a == "--steps") steps = std::strtoull(next().c_str(), nullptr, 10);
        else if (a == "--rounds") rounds = std::max(1, std::atoi(next().c_str()));
        else if (a == "--json") json_out = next();
        else if (a == "--compare") compare_file = next();
        else if (a == "--agree-from") agree_from_s = std::strtod(next().c_str(), nullptr);
        else if (a == "--variants") variants_arg = next();
        else if (a == "--dump") dump_prefix = next();
        else if (a == "--leakwatch-json") rust_jsons.push_back(next());
        else if (a == "--leakwatch") leakwatch_bin = next();
        else if (a == "--bench-dir") bench_dir = next();
        else usage();
    }
    if (csv.empty()) usage();
    std::vector<Variant> variants;
    for (const auto& v : split(variants_arg)) {
        if (v == "joseph") variants.push_back(Variant::Joseph);
        else if (v == "selector") variants.push_back(Variant::Selector);
        else if (v == "sqrt") variants.push_back(Variant::Sqrt);
        else if (v == "joseph8") variants.push_back(Variant::Joseph8);
        else usage();
    }

    const Params params;
    const Tuning tuning;
    const Model model(params, tuning.dt_s);
    // The samples: every channel must be usable (the peer has no channel drop-out;
    // leakwatch's measured range is [-0.02 p_s, 1.5 p_s] for the pressures).
    const auto cols = read_columns(csv, {"t", "u", "x", "p1", "p2"});
    std::vector<Sample> samples;
    const double p_lo = -0.02 * params.supply_pressure_pa, p_hi = 1.5 * params.supply_pressure_pa;
    for (size_t k = 0; k < cols[0].size(); ++k) {
        const Sample s{cols[0][k], cols[1][k], cols[2][k], cols[3][k], cols[4][k]};
        const bool ok = std::isfinite(s.u) && std::isfinite(s.x) && std::isfinite(s.p1) && std::isfinite(s.p2) &&
                        s.p1 >= p_lo && s.p1 <= p_hi && s.p2 >= p_lo && s.p2 <= p_hi;
        if (!ok) {
            std::fprintf(stderr, "ekf_peer: %s row %zu has an unusable channel; the peer needs complete samples\n",
                         csv.c_str(), k + 2);
            return 2;
        }
        samples.push_back(s);
    }
    if (samples.empty()) {
        std::fprintf(stderr, "ekf_peer: %s has no samples\n", csv.c_str());
        return 2;
    }
    const Runner runner{model, tuning, samples};

    // ---- every estimate of each variant, PREFIX.VARIANT.csv (for a closer look)
    if (!dump_prefix.empty())
        for (const Variant v : variants) {
            const std::string path = dump_prefix + "." + variant_name(v) + ".csv";
            std::FILE* out = std::fopen(path.c_str(), "w");
            if (!out) {
                std::fprintf(stderr, "ekf_peer: cannot write %s\n", path.c_str());
                return 1;
            }
            std::fprintf(out, "t,th_x,th_p1,th_p2,th_v,th_f_e,th_nis\n");
            const auto est = runner.estimates(v);
            for (size_t k = 0; k < est.size(); ++k) {
                std::fprintf(out, "%.17g", samples[k].t);
                for (const double e : est[k]) std::fprintf(out, ",%.17g", e);
                std::fprintf(out, "\n");
            }
            std::fclose(out);
        }

    // ---- agreement with leakwatch's estimates of the same CSV
    std::ostringstream agreement_json;
    if (!compare_file.empty()) {
        const std::vector<std::string> names(COLS, COLS + 6);
        const auto ref = read_columns(compare_file, names);
        if (ref[0].size() != samples.size())
            std::fprintf(stderr, "ekf_peer: %s has %zu rows, %s %zu samples\n", compare_file.c_str(), ref[0].size(),
                         csv.c_str(), samples.size());
        const size_t n = std::min(ref[0].size(), samples.size());
        size_t from = 0;
        while (from < n && samples[from].t - samples[0].t < agree_from_s) ++from;
        std::printf("Agreement with leakwatch's 7-state thesis filter (%s), %zu samples: per column the largest "
                    "|difference| over the largest |value| of leakwatch's column, over the whole stream and from "
                    "%g s on (sample %zu)\n",
                    compare_file.c_str(), n, agree_from_s, from);
        std::printf("| variant | from | x | p1 | p2 | v | F_e | NIS | covariance not positive definite after the update |\n");
        std::printf("|---|---|---|---|---|---|---|---|---|\n");
        agreement_json << "{\"from_s\": " << agree_from_s << ", \"from_sample\": " << from << ", \"samples\": " << n
                       << ", \"variants\": [";
        bool first = true;
        for (const Variant v : variants) {
            size_t indefinite = 0;
            const auto est = runner.estimates(v, &indefinite);
            const Agreement whole = compare(est, ref, 0), tail = compare(est, ref, from);
            for (const auto& [label, a] : {std::pair<std::string, const Agreement&>{"0 s", whole},
                                           std::pair<std::string, const Agreement&>{std::to_string(agree_from_s).substr(0, 4) + " s", tail}}) {
                std::printf("| %s | %s |", variant_name(v), label.c_str());
                for (int c = 0; c < 6; ++c) std::printf(" %.1e |", a.rel[c]);
                std::printf(" %s |\n", v == Variant::Sqrt ? "– (S Sᵀ)" : std::to_string(indefinite).append(" samples").c_str());
            }
            agreement_json << (first ? "" : ",") << "\n    {\"variant\": \"" << variant_name(v)
                           << "\", \"indefinite_samples\": " << indefinite;
            agreement_json.precision(3);
            for (const auto& [key, a] : {std::pair<std::string, const Agreement&>{"whole", whole},
                                         std::pair<std::string, const Agreement&>{"from", tail}}) {
                agreement_json << ", \"" << key << "\": {\"max_rel_states\": " << std::scientific << a.worst();
                for (int c = 0; c < 6; ++c)
                    agreement_json << ", \"" << COLS[c] << "\": " << std::scientific << a.rel[c] << std::defaultfloat;
                agreement_json << "}";
            }
            agreement_json << "}";
            first = false;
        }
        agreement_json << "\n  ]}";
        std::printf("\n");
    }

    // ---- timing
    // (--steps 0: the agreement alone.) Each round times every C++ variant and
    // then, with --leakwatch, runs `leakwatch bench ekf` once, so both sides
    // see the same load; the figures are medians over rounds.
    const double overhead = steps > 0 ? timer_overhead_ns(100000) : 0.0;
    struct Row {
        std::string label;
        int states = 7;
        std::vector<double> medians, p99s, p999s, means, overheads;
        uint64_t steps = 0;
    };
    std::vector<Row> rows;  // the C++ variants
    std::vector<Row> rust;  // leakwatch's filters, in ekf.json's order
    auto add_rust = [&](const std::string& file) {
        const auto rr = read_rust_json(file);
        if (rr.empty()) {
            std::fprintf(stderr, "ekf_peer: no step_time rows in %s\n", file.c_str());
            return false;
        }
        for (size_t i = 0; i < rr.size(); ++i) {
            if (i >= rust.size()) rust.push_back(Row{rr[i].filter, rr[i].states, {}, {}, {}, {}, {}, 0});
            rust[i].medians.push_back(rr[i].median_ns);
            rust[i].p99s.push_back(rr[i].p99_ns);
            rust[i].overheads.push_back(rr[i].timer_overhead_ns);
        }
        return true;
    };
    for (const auto& file : rust_jsons)
        if (!add_rust(file)) return 1;
    if (steps > 0)
        for (const Variant v : variants) rows.push_back(Row{variant_label(v), 7, {}, {}, {}, {}, {}, 0});
    for (int r = 0; r < rounds && steps > 0; ++r) {
        for (size_t i = 0; i < rows.size(); ++i) {
            auto ns = runner.time_steps(variants[i], steps);
            double sum = 0.0;
            for (const double d : ns) sum += d;
            std::sort(ns.begin(), ns.end());
            rows[i].medians.push_back(quantile_sorted(ns, 0.5));
            rows[i].p99s.push_back(quantile_sorted(ns, 0.99));
            rows[i].p999s.push_back(quantile_sorted(ns, 0.999));
            rows[i].means.push_back(sum / static_cast<double>(ns.size()));
            rows[i].steps = ns.size();
        }
        if (!leakwatch_bin.empty()) {
            const std::string dir = bench_dir + "/round-" + std::to_string(r + 1);
            const std::string cmd = shell_quote(leakwatch_bin) + " bench ekf --steps " + std::to_string(steps) + " --out " +
                                    shell_quote(dir) + " --force > " + shell_quote(dir + ".log") + " 2>&1";
            std::fprintf(stderr, "round %d: leakwatch bench ekf (%s.log)\n", r + 1, dir.c_str());
            if (std::system(cmd.c_str()) != 0) {
                std::fprintf(stderr, "ekf_peer: `%s` failed (see %s.log)\n", cmd.c_str(), dir.c_str());
                return 1;
            }
            if (!add_rust(dir + "/ekf.json")) return 1;
        }
    }
    const double ref_median = rows.empty() ? NAN : median(rows[0].medians);
    // the padded Joseph peer, the fastest covariance form here, as a second yardstick
    double ref8 = NAN;
    for (size_t i = 0; i < rows.size(); ++i)
        if (variants[i] == Variant::Joseph8) ref8 = median(rows[i].medians);
    if (!rows.empty()) {
        std::printf("Each predict + update timed on its own with the monotonic clock (steady_clock); every figure "
                    "includes the clock's own cost, %.0f ns here. %d rounds of %llu steps per variant (%zu samples, "
                    "looped), median over rounds.\n",
                    overhead, rounds, static_cast<unsigned long long>(rows[0].steps), samples.size());
        std::printf("| filter | median ns | p99 ns | p99.9 ns | mean ns | round medians ns | vs joseph |\n");
        std::printf("|---|---|---|---|---|---|---|\n");
        for (const auto& row : rows) {
            std::string each;
            for (const double m : row.medians) each += (each.empty() ? "" : ", ") + std::to_string(std::lround(m));
            std::printf("| %s | %.0f | %.0f | %.0f | %.0f | %s | %.2f |\n", row.label.c_str(), median(row.medians),
                        median(row.p99s), median(row.p999s), median(row.means), each.c_str(),
                        median(row.medians) / ref_median);
        }
    }
    if (!rust.empty() && !rows.empty()) {
        std::printf("\nBoth sides, interleaved, medians over rounds (%zu of leakwatch's `bench ekf`); every figure "
                    "includes its side's clock cost (C++ %.0f ns, leakwatch %.0f ns):\n",
                    rust[0].medians.size(), overhead, median(rust[0].overheads));
        std::printf("| filter | states | median ns | p99 ns | vs C++ Joseph | vs C++ Joseph 8×8 |\n|---|---|---|---|---|---|\n");
        for (const auto& row : rows)
            std::printf("| %s | %d | %.0f | %.0f | %.2f | %.2f |\n", row.label.c_str(), row.states, median(row.medians),
                        median(row.p99s), median(row.medians) / ref_median, median(row.medians) / ref8);
        for (const auto& row : rust)
            std::printf("| leakwatch: %s (`bench ekf`) | %d | %.0f | %.0f | %.2f | %.2f |\n", row.label.c_str(), row.states,
                        median(row.medians), median(row.p99s), median(row.medians) / ref_median,
                        median(row.medians) / ref8);
    }

    if (!json_out.empty()) {
        std::ofstream js(json_out);
        auto list = [&](const std::vector<double>& v) {
            std::string out = "[";
            for (size_t k = 0; k < v.size(); ++k) out += (k ? ", " : "") + std::to_string(v[k]);
            return out + "]";
        };
        js << "{\n  \"benchmark\": \"ekf_peer\",\n  \"states\": 7,\n  \"csv\": " << json_string(csv)
           << ",\n  \"samples\": " << samples.size() << ",\n  \"steps_per_round\": " << (rows.empty() ? 0 : rows[0].steps)
           << ",\n  \"rounds\": " << rounds << ",\n  \"timer_overhead_ns\": " << overhead
           << ",\n  \"ratio_to\": \"vs_cpp_joseph: the C++ Joseph peer (7×7, dense H); vs_cpp_joseph8: the same padded to 8×8; medians\",\n  \"filters\": [";
        for (size_t i = 0; i < rows.size(); ++i) {
            const auto& row = rows[i];
            js << (i ? "," : "") << "\n    {\"side\": \"c++\", \"variant\": \"" << variant_name(variants[i])
               << "\", \"filter\": " << json_string(row.label) << ", \"states\": 7, \"median_ns\": " << median(row.medians)
               << ", \"p99_ns\": " << median(row.p99s) << ", \"p999_ns\": " << median(row.p999s)
               << ", \"mean_ns\": " << median(row.means) << ", \"vs_cpp_joseph\": " << median(row.medians) / ref_median
               << ", \"vs_cpp_joseph8\": " << median(row.medians) / ref8 << ", \"round_medians_ns\": " << list(row.medians) << "}";
        }
        for (size_t i = 0; i < rust.size(); ++i) {
            const auto& row = rust[i];
            js << (i || !rows.empty() ? "," : "") << "\n    {\"side\": \"leakwatch\", \"filter\": " << json_string(row.label)
               << ", \"states\": " << row.states << ", \"median_ns\": " << median(row.medians)
               << ", \"p99_ns\": " << median(row.p99s) << ", \"timer_overhead_ns\": " << median(row.overheads)
               << ", \"vs_cpp_joseph\": " << median(row.medians) / ref_median
               << ", \"vs_cpp_joseph8\": " << median(row.medians) / ref8 << ", \"round_medians_ns\": " << list(row.medians) << "}";
        }
        js << "\n  ]";
        if (!compare_file.empty()) js << ",\n  \"agreement\": " << agreement_json.str();
        js << "\n}\n";
        if (!js) {
            std::fprintf(stderr, "ekf_peer: cannot write %s\n", json_out.c_str());
            return 1;
        }
    }
    return 0;
}
