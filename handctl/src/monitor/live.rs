//! The daemon's subscription lines (`{"cmd":"subscribe"}` on the control socket), applied to
//! the monitor's state.
//!
//! [`Live`] is the daemon's own type (`driver::live`): one schema for both ends. Unknown fields
//! are ignored, as the schema allows fields to be added.

use super::state::MonitorState;

pub use driver::live::Live;

impl MonitorState {
    /// Takes one live line: everything it carries replaces what was shown, then one plot point.
    pub fn apply_live(&mut self, l: &Live) {
        self.t_us = l.t_us;
        if self.channels.len() != l.channels.len() {
            self.channels.resize(l.channels.len(), Default::default());
        }
        for (c, (v, ch)) in self.channels.iter_mut().zip(&l.channels).enumerate() {
            v.rms_uv = ch.rms_uv;
            v.lead_off = ch.lead_off;
            v.saturated = ch.saturated;
            v.rest_uv = l.rest_rms_uv.as_ref().and_then(|r| r.get(c).copied());
        }
        for (v, f) in self.fingers.iter_mut().zip(&l.fingers) {
            v.label = Some(f.label);
            v.force_n = f.force_n;
            v.velocity_rad_s = f.velocity_rad_s;
            v.position_rad = f.reported_position_rad;
            v.reported_force_n = f.reported_force_n;
            v.disabled = f.disabled;
            v.active = f.active;
        }
        self.drives.clone_from(&l.drives);
        let d = &mut self.daemon;
        d.state = Some(l.state.clone());
        d.faults.clone_from(&l.faults);
        d.model_id = (!l.model.id.is_empty()).then(|| l.model.id.clone());
        d.model_detail = (!l.model.kind.is_empty() || !l.model.path.is_empty()).then(|| {
            format!("{} {}", l.model.kind, l.model.path)
                .trim()
                .to_owned()
        });
        d.latency_p50_us = Some(l.latency_us.p50_us);
        d.latency_p99_us = Some(l.latency_us.p99_us);
        d.deadline_misses = l.counters.deadline_misses;
        d.e2e_errors = l.counters.e2e_errors;
        d.samples_lost = l.counters.samples_lost;
        d.beyond_calibration = l.counters.beyond_calibration;
        d.implausible = l.counters.implausible;
        d.bus_load = Some(l.bus_load);
        if !l.bus.controller.is_empty() {
            let c = &l.bus.counters;
            let errors = c.warning
                + c.passive
                + c.bus_off
                + c.no_ack
                + c.controller_overflow
                + c.protocol
                + c.other
                + c.tx_queue_full;
            d.can = Some(format!("{}, {errors} errors", l.bus.controller));
        }
        self.update_noisy();
        self.sample_history();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_line_of_the_schema_fills_the_state() {
        let line = r#"{"t_us":5000000,"tick":100,"state":"RUNNING","faults":[],
            "model":{"id":"1a2b3c4d","path":"/var/lib/handstack/model.hsm","kind":"ResDD"},
            "latency_us":{"count":10,"p50_us":800,"p99_us":1500,"max_us":2000},
            "compute_us":{"count":10,"p50_us":20,"p99_us":40,"max_us":50},
            "counters":{"deadline_misses":2,"samples_lost":3,"e2e_errors":4,"bad_frames":0,
                        "frames_rx":1,"frames_tx":2},
            "bus_load":0.46,
            "channels":[{"rms_uv":12.5,"lead_off":true,"saturated":false},
                        {"rms_uv":3.0,"lead_off":false,"saturated":true}],
            "rest_rms_uv":[2.0,2.5],
            "fingers":[{"label":0.5,"force_n":5.0,"velocity_rad_s":0.1,
                        "reported_position_rad":0.7,"reported_force_n":4.5,
                        "disabled":false,"active":true}],
            "a_field_added_later":1}"#;
        let live: Live = serde_json::from_str(line).expect("the schema parses");
        let mut s = MonitorState::new("daemon", 12);
        s.apply_live(&live);
        assert_eq!(s.channels.len(), 2);
        assert_eq!(s.channels[0].rms_uv, 12.5);
        assert!(s.channels[0].lead_off && s.channels[1].saturated);
        assert_eq!(s.channels[1].rest_uv, Some(2.5));
        assert_eq!(s.fingers[0].label, Some(0.5));
        assert!(s.fingers[0].active);
        assert_eq!(s.daemon.state.as_deref(), Some("RUNNING"));
        assert_eq!(s.daemon.model_id.as_deref(), Some("1a2b3c4d"));
        assert_eq!(
            (s.daemon.latency_p50_us, s.daemon.latency_p99_us),
            (Some(800), Some(1500))
        );
        assert_eq!(s.daemon.deadline_misses, 2);
        assert_eq!(s.history.len(), 1);
        assert_eq!(s.t_us, 5_000_000);
        assert!(s.drives.is_empty(), "every finger native: no drive line");
        let with_drive = line.replace(
            r#""a_field_added_later":1"#,
            r#""drives":[{"finger":"index","node":6,"state":"Operation enabled",
                "faulted":false,"nmt":"operational","power_state":"Operation enabled",
                "feedback_age_ms":12}]"#,
        );
        let live: Live = serde_json::from_str(&with_drive).expect("the schema parses");
        s.apply_live(&live);
        assert_eq!(s.drives.len(), 1);
        assert_eq!(
            (s.drives[0].node, s.drives[0].feedback_age_ms),
            (6, Some(12))
        );
    }
}
