//! The back-support exoskeleton of Shojaei Barjuei et al. (Designs 2020, 4, 53) end to end.
fn main() {
    let cfg = bgc_workspace::back_support::scenario::ScenarioConfig::paper();
    let t0 = std::time::Instant::now();
    match bgc_workspace::back_support::study(&cfg) {
        Ok(s) => {
            let mc = &s.model_check;
            println!("model check {} {} {} {}", mc.max_torque_difference, mc.max_velocity_difference, mc.max_torque_difference_as_printed, mc.max_velocity_difference_as_printed);
            println!("single {:?}\nrepro {:?}\ndouble {:?}", s.lqr.single.k, s.lqr.single_reproducing.k, s.lqr.double.k);
            for c in &s.seven_state { println!("{} det {} modes {:?} lqe {:?}", c.name, c.detectable, c.unobservable.iter().map(|m| m.eigenvalue).collect::<Vec<_>>(), c.lqe.as_ref().err().map(|e| e.to_string())); }
            println!("obs L {}", s.observer.continuous.l);
            println!("M {}", s.observer.discrete.filter_gain);
            let r = &s.scenario;
            println!("peak {} at {} mse yb {} mse wm {} true {}", r.peak_motor_torque, r.peak_time, r.human_torque_mse, r.motor_velocity_mse, r.motor_velocity_mse_true);
            let rb = &s.robustness;
            println!("obs loop {:?}", rb.observer_loop);
            println!("sf loop {:?}", rb.state_feedback_loop);
            println!("dist dc {} peak {} at {} Hz bw {:?}", rb.disturbance_dc_gain, rb.disturbance_peak_gain, rb.disturbance_peak_frequency_hz, rb.rejection_bandwidth_hz);
        }
        Err(e) => eprintln!("error: {e}"),
    }
    println!("{:?}", t0.elapsed());
}
