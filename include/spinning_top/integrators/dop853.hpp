// DOP853: the explicit Runge-Kutta pair of order 8(5,3) by Dormand & Prince with Hairer's
// error estimator and 7th-order dense output (Hairer, Norsett, Wanner, Solving ODEs I, 2nd ed.
// 1993, sec. II.10; coefficients of Hairer's dop853.f, as tabulated in SciPy's
// integrate/_ivp/dop853_coefficients.py). 12 stages per step (the 13th, f(y1), is the next
// step's first), 3 more for the dense output of an accepted step, evaluated only for a step in
// which dense output is actually asked for (complete_dense()). For smooth non-stiff problems at
// tight tolerances it needs far fewer steps than dopri5.
#pragma once

#include <Eigen/Core>
#include <cmath>

#include "spinning_top/hot_path.hpp"
#include "spinning_top/integration/controllers.hpp"

namespace spinning_top {

template <class Model>
class DormandPrince853 {
 public:
  using State = typename Model::State;
  static constexpr int kOrder = 8;
  static constexpr int kEmbeddedOrder = 7;  // Hairer's combined 5th/3rd-order estimate scales as dt^8
  using Controller = PiController<kEmbeddedOrder + 1>;  // the estimate is O(dt^(kEmbeddedOrder + 1))
  static constexpr int kStagesPerStep = 12;
  static constexpr const char* kName = "dop853";

  struct Attempt {
    State y1;     // eighth-order solution
    State f1;     // f(y1)
    State error;  // a vector whose RMS norm is Hairer's error estimate (see attempt())
  };

  struct DenseStep {
    State y0;
    State f[7];  // coefficients of the continuous extension (see dense())
    double t0 = 0.0, dt = 0.0;
  };

  SPINNING_TOP_FLATTEN void attempt(const Model& model, const State& y0, const State& f0, double dt, Attempt& out) {
    work_ += kStagesPerStep;
    k_[0] = f0;
    for (int s = 1; s < 12; ++s) model.derivative(stage_start(y0, dt, s), k_[s]);
    out.y1 = stage_start(y0, dt, 12);
    model.derivative(out.y1, out.f1);
    k_[12] = out.f1;
    State err5 = State::Zero(), err3 = State::Zero();
    for (int j = 0; j < 12; ++j) {
      err5 += kE5[j] * k_[j];
      err3 += (kA[12][j] - kE3Correction[j]) * k_[j];
    }
    // Hairer's estimate err = |e5|^2 / sqrt(|e5|^2 + 0.01 |e3|^2) (dop853.f): written as e5
    // times the ratio |e5| / sqrt(...), which does not depend on the tolerance (it cancels),
    // so the driver's RMS norm of `error` is exactly Hairer's err.
    const State scale = (1.0 + y0.cwiseAbs().cwiseMax(out.y1.cwiseAbs()).array()).matrix();
    const double n5 = err5.cwiseQuotient(scale).squaredNorm(), n3 = err3.cwiseQuotient(scale).squaredNorm();
    const double denominator = std::sqrt(n5 + 0.01 * n3);
    const double ratio = denominator > 0.0 ? std::sqrt(n5) / denominator : 1.0;
    out.error = (dt * ratio) * err5;
  }

  /// Nothing is kept from step to step.
  void restart() {}

  /// Continuous extension of the step just accepted, first part: the cubic Hermite terms,
  /// which need no more evaluations of f. dense() needs complete_dense() as well.
  SPINNING_TOP_FLATTEN void prepare_dense(const State& y0, const State& f0, const Attempt& a, double t0, double dt,
                                          DenseStep& d) const {
    const State delta = a.y1 - y0;
    d.y0 = y0;
    d.f[0] = delta;
    d.f[1] = dt * f0 - delta;
    d.f[2] = 2.0 * delta - dt * (a.f1 + f0);
    d.t0 = t0;
    d.dt = dt;
  }

  /// Second part: the three extra stages and the seventh-order terms. It reads the stages
  /// k_ of the step, so it must come before the next attempt(). Split off because most
  /// steps of a run with sparse output (or none) never need it: it costs 3 of the 15
  /// evaluations of f and the 4 x 12 vector terms of kD.
  SPINNING_TOP_FLATTEN void complete_dense(const Model& model, DenseStep& d) {
    work_ += kDenseStages;
    for (int s = 13; s < 16; ++s) model.derivative(stage_start(d.y0, d.dt, s), k_[s]);
    for (int i = 0; i < 4; ++i) {
      State sum = State::Zero();
      for (int j = 0; j < 16; ++j)
        if (kD[i][j] != 0.0) sum += kD[i][j] * k_[j];
      d.f[3 + i] = d.dt * sum;
    }
  }

  /// Work units spent (work_budget.hpp): the evaluations of f of its attempts and dense outputs.
  long work() const { return work_; }

  /// y(t0 + x dt), seventh order: the nested form of dop853.f's CONTD8.
  SPINNING_TOP_FLATTEN static State dense(const DenseStep& d, double t) {
    const double x = (t - d.t0) / d.dt;
    State y = State::Zero();
    for (int i = 6; i >= 0; --i) {
      y += d.f[i];
      y *= ((6 - i) % 2 == 0) ? x : 1.0 - x;
    }
    return d.y0 + y;
  }

 private:
  State stage_start(const State& y0, double dt, int s) const {
    State sum = State::Zero();
    for (int j = 0; j < s; ++j)
      if (kA[s][j] != 0.0) sum += kA[s][j] * k_[j];
    return y0 + dt * sum;
  }

  State k_[16];
  long work_ = 0;
  static constexpr int kDenseStages = 3;

  static constexpr double kA[16][16] = {
      {0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0},
      {5.26001519587677318785587544488e-2, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0},
      {1.97250569845378994544595329183e-2, 5.91751709536136983633785987549e-2, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0},
      {2.95875854768068491816892993775e-2, 0, 8.87627564304205475450678981324e-2, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0},
      {2.41365134159266685502369798665e-1, 0, -8.84549479328286085344864962717e-1, 9.24834003261792003115737966543e-1, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0},
      {3.7037037037037037037037037037e-2, 0, 0, 1.70828608729473871279604482173e-1, 1.25467687566822425016691814123e-1, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0},
      {3.7109375e-2, 0, 0, 1.70252211019544039314978060272e-1, 6.02165389804559606850219397283e-2, -1.7578125e-2, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0},
      {3.70920001185047927108779319836e-2, 0, 0, 1.70383925712239993810214054705e-1, 1.07262030446373284651809199168e-1, -1.53194377486244017527936158236e-2, 8.27378916381402288758473766002e-3, 0, 0, 0, 0, 0, 0, 0, 0, 0},
      {6.24110958716075717114429577812e-1, 0, 0, -3.36089262944694129406857109825, -8.68219346841726006818189891453e-1, 2.75920996994467083049415600797e1, 2.01540675504778934086186788979e1, -4.34898841810699588477366255144e1, 0, 0, 0, 0, 0, 0, 0, 0},
      {4.77662536438264365890433908527e-1, 0, 0, -2.48811461997166764192642586468, -5.90290826836842996371446475743e-1, 2.12300514481811942347288949897e1, 1.52792336328824235832596922938e1, -3.32882109689848629194453265587e1, -2.03312017085086261358222928593e-2, 0, 0, 0, 0, 0, 0, 0},
      {-9.3714243008598732571704021658e-1, 0, 0, 5.18637242884406370830023853209, 1.09143734899672957818500254654, -8.14978701074692612513997267357, -1.85200656599969598641566180701e1, 2.27394870993505042818970056734e1, 2.49360555267965238987089396762, -3.0467644718982195003823669022, 0, 0, 0, 0, 0, 0},
      {2.27331014751653820792359768449, 0, 0, -1.05344954667372501984066689879e1, -2.00087205822486249909675718444, -1.79589318631187989172765950534e1, 2.79488845294199600508499808837e1, -2.85899827713502369474065508674, -8.87285693353062954433549289258, 1.23605671757943030647266201528e1, 6.43392746015763530355970484046e-1, 0, 0, 0, 0, 0},
      {5.42937341165687622380535766363e-2, 0, 0, 0, 0, 4.45031289275240888144113950566, 1.89151789931450038304281599044, -5.8012039600105847814672114227, 3.1116436695781989440891606237e-1, -1.52160949662516078556178806805e-1, 2.01365400804030348374776537501e-1, 4.47106157277725905176885569043e-2, 0, 0, 0, 0},
      {5.61675022830479523392909219681e-2, 0, 0, 0, 0, 0, 2.53500210216624811088794765333e-1, -2.46239037470802489917441475441e-1, -1.24191423263816360469010140626e-1, 1.5329179827876569731206322685e-1, 8.20105229563468988491666602057e-3, 7.56789766054569976138603589584e-3, -8.298e-3, 0, 0, 0},
      {3.18346481635021405060768473261e-2, 0, 0, 0, 0, 2.83009096723667755288322961402e-2, 5.35419883074385676223797384372e-2, -5.49237485713909884646569340306e-2, 0, 0, -1.08347328697249322858509316994e-4, 3.82571090835658412954920192323e-4, -3.40465008687404560802977114492e-4, 1.41312443674632500278074618366e-1, 0, 0},
      {-4.28896301583791923408573538692e-1, 0, 0, 0, 0, -4.69762141536116384314449447206, 7.68342119606259904184240953878, 4.06898981839711007970213554331, 3.56727187455281109270669543021e-1, 0, 0, 0, -1.39902416515901462129418009734e-3, 2.9475147891527723389556272149, -9.15095847217987001081870187138, 0},
  };
  static constexpr double kE5[12] = {0.1312004499419488073250102996e-1, 0, 0, 0, 0, -0.1225156446376204440720569753e1, -0.4957589496572501915214079952, 0.1664377182454986536961530415e1, -0.3503288487499736816886487290, 0.3341791187130174790297318841, 0.8192320648511571246570742613e-1, -0.2235530786388629525884427845e-1};
  // E3 = b - bhat3, nonzero where b or bhat3 is.
  static constexpr double kE3Correction[12] = {0.244094488188976377952755905512, 0, 0, 0, 0, 0, 0, 0, 0.733846688281611857341361741547, 0, 0, 0.220588235294117647058823529412e-1};
  static constexpr double kD[4][16] = {
      {-0.84289382761090128651353491142e1, 0, 0, 0, 0, 0.56671495351937776962531783590, -0.30689499459498916912797304727e1, 0.23846676565120698287728149680e1, 0.21170345824450282767155149946e1, -0.87139158377797299206789907490, 0.22404374302607882758541771650e1, 0.63157877876946881815570249290, -0.88990336451333310820698117400e-1, 0.18148505520854727256656404962e2, -0.91946323924783554000451984436e1, -0.44360363875948939664310572000e1},
      {0.10427508642579134603413151009e2, 0, 0, 0, 0, 0.24228349177525818288430175319e3, 0.16520045171727028198505394887e3, -0.37454675472269020279518312152e3, -0.22113666853125306036270938578e2, 0.77334326684722638389603898808e1, -0.30674084731089398182061213626e2, -0.93321305264302278729567221706e1, 0.15697238121770843886131091075e2, -0.31139403219565177677282850411e2, -0.93529243588444783865713862664e1, 0.35816841486394083752465898540e2},
      {0.19985053242002433820987653617e2, 0, 0, 0, 0, -0.38703730874935176555105901742e3, -0.18917813819516756882830838328e3, 0.52780815920542364900561016686e3, -0.11573902539959630126141871134e2, 0.68812326946963000169666922661e1, -0.10006050966910838403183860980e1, 0.77771377980534432092869265740, -0.27782057523535084065932004339e1, -0.60196695231264120758267380846e2, 0.84320405506677161018159903784e2, 0.11992291136182789328035130030e2},
      {-0.25693933462703749003312586129e2, 0, 0, 0, 0, -0.15418974869023643374053993627e3, -0.23152937917604549567536039109e3, 0.35763911791061412378285349910e3, 0.93405324183624310003907691704e2, -0.37458323136451633156875139351e2, 0.10409964950896230045147246184e3, 0.29840293426660503123344363579e2, -0.43533456590011143754432175058e2, 0.96324553959188282948394950600e2, -0.39177261675615439165231486172e2, -0.14972683625798562581422125276e3},
  };
};

}  // namespace spinning_top
