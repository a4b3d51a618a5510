//! One sample of measured (or simulated) rig data: the row of the CSV format
//! of ARCHITECTURE.md (`t,u,x,p1,p2,x_sp,f_load,ref,q_leak,temp_c`).

/// One 1 kHz sample of the rig. Optional channels are NaN when absent.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sample {
    /// Sample time, s.
    pub t_s: f64,
    /// Valve command applied from this sample to the next, V.
    pub u_v: f64,
    /// Measured rod position, m.
    pub x_m: f64,
    /// Measured chamber-1 pressure, Pa.
    pub p1_pa: f64,
    /// Measured chamber-2 pressure, Pa.
    pub p2_pa: f64,
    /// Measured spool position, m (NaN if absent).
    pub x_sp_m: f64,
    /// Measured external load force (load cell), N (NaN if absent).
    pub f_load_n: f64,
    /// Position reference of the controller, m (NaN in open loop or if absent).
    pub ref_m: f64,
    /// Leak flow (flow meter, or the simulator's truth), L/min (NaN if absent);
    /// signed along the leak path, chamber 1 to chamber 2 for the internal leak.
    pub q_leak_lpm: f64,
    /// Oil temperature, °C (NaN if absent).
    pub temp_c: f64,
}

impl Sample {
    /// A sample with the required channels and every optional one absent.
    pub fn new(t_s: f64, u_v: f64, x_m: f64, p1_pa: f64, p2_pa: f64) -> Self {
        Sample {
            t_s,
            u_v,
            x_m,
            p1_pa,
            p2_pa,
            x_sp_m: f64::NAN,
            f_load_n: f64::NAN,
            ref_m: f64::NAN,
            q_leak_lpm: f64::NAN,
            temp_c: f64::NAN,
        }
    }

    /// Every channel in the CSV column order `t,u,x,p1,p2,x_sp,f_load,ref,q_leak,temp_c`
    /// (s, V, m, Pa, Pa, m, N, m, L/min, °C).
    pub fn columns(&self) -> [f64; 10] {
        [
            self.t_s,
            self.u_v,
            self.x_m,
            self.p1_pa,
            self.p2_pa,
            self.x_sp_m,
            self.f_load_n,
            self.ref_m,
            self.q_leak_lpm,
            self.temp_c,
        ]
    }

    /// The measurement vector of the estimator, [x (m), p1 (Pa), p2 (Pa)].
    pub fn measurement(&self) -> [f64; 3] {
        [self.x_m, self.p1_pa, self.p2_pa]
    }
}
