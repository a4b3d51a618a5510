//! The field list of every frame type, in declaration order, as one macro
//! ([`frame_fields!`](crate::frame_fields)) for code that handles each field by
//! name: the recorder's JSON and CSV records and the layout tests.

/// Hands the fields of a frame type, in declaration order and padding
/// included, to another macro: `frame_fields!(EstimateFrame, m!(ARGS))`
/// expands to `m!(ARGS [seq, acq_mono_ns, ...])`. The first argument is one of
/// `SensorFrame`, `EstimateFrame`, `LeakEventFrame`, `HealthFrame`,
/// `StatsFrame`; every list is checked at compile time to name every field of
/// its type once.
#[macro_export]
macro_rules! frame_fields {
    (SensorFrame, $m:ident!($($args:tt)*)) => {
        $m! {$($args)* [
            seq, acq_mono_ns, t_s, u_v, x_m, p1_pa, p2_pa, x_sp_m, f_load_n, ref_m, q_leak_lpm,
            flags, _pad, temp_c
        ]}
    };
    (EstimateFrame, $m:ident!($($args:tt)*)) => {
        $m! {$($args)* [
            seq, acq_mono_ns, est_recv_mono_ns, est_done_mono_ns, t_s, n_states, flags, state,
            state_sigma, residual, innovation, innovation_sigma, measured, u_v, nis, mae_pa,
            th_flags, _pad, th_state, th_residual, th_innovation, th_mae_pa, th_nis, bulk_scale,
            bulk_scale_sigma, oil_temp_c, oil_temp_sigma_k, laminar_factor_sigma,
            null_leakage_band_lpm, offset_response_p1_lpm_per_mpa, offset_response_p2_lpm_per_mpa,
            span_response_p1_lpm, span_response_p2_lpm, offset_response_x_lpm_per_mm,
            delay_response_p1_lpm_per_ms, delay_response_p2_lpm_per_ms
        ]}
    };
    (LeakEventFrame, $m:ident!($($args:tt)*)) => {
        $m! {$($args)* [
            seq, acq_mono_ns, cls_done_mono_ns, event_id, kind, phase, t_detect_s, t_onset_s,
            size_lpm, size_lpm_sigma, confidence, detector, size_nominal_lpm,
            coefficient_m3_s_sqrt_pa, statistic, threshold, channel, detail
        ]}
    };
    (HealthFrame, $m:ident!($($args:tt)*)) => {
        $m! {$($args)* [
            seq, mono_ns, t_s, status, active_events, leak_flow_lpm, leak_flow_sigma_lpm,
            leak_threshold_lpm
        ]}
    };
    (StatsFrame, $m:ident!($($args:tt)*)) => {
        $m! {$($args)* [
            mono_ns, pid, stage, frames_in, frames_out, seq_gaps, deadline_misses, proc_ns_p50,
            proc_ns_p99, proc_ns_max, lat_ns_p50, lat_ns_p99, lat_ns_max, cpu_fraction, rss_bytes
        ]}
    };
}

/// A compile-time check that a field list names every field of `$ty` once (a
/// pattern without `..`); the order is checked against the offsets by tests/layout.rs.
macro_rules! all_fields {
    ($ty:ident [$($field:ident),*]) => {
        const _: fn(crate::$ty) = |f| {
            let crate::$ty { $($field: _),* } = f;
        };
    };
}

frame_fields!(SensorFrame, all_fields!(SensorFrame));
frame_fields!(EstimateFrame, all_fields!(EstimateFrame));
frame_fields!(LeakEventFrame, all_fields!(LeakEventFrame));
frame_fields!(HealthFrame, all_fields!(HealthFrame));
frame_fields!(StatsFrame, all_fields!(StatsFrame));
