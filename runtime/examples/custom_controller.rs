//! Writing a controller in Rust against the Khepera API, and running it in a world.
//!
//! `cargo run --release -p regatta-runtime --example custom_controller -- worlds/regatta.wbt`
//!
//! The same `Controller` drives a real Khepera through a serial backend of the same API: the
//! units are the real robot's (speeds in pulses per 10 ms, sensors 0…1023).

use regatta_runtime::khepera::{Controller, Khepera, KheperaError, LedAction};
use regatta_runtime::sim::Simulation;

/// Wanders, turning away from whichever side sees more, and blinks LED 0 while it turns.
struct Wanderer {
    steps: u64,
}

impl Controller for Wanderer {
    fn step(&mut self, robot: &mut dyn Khepera) -> Result<(), KheperaError> {
        self.steps += 1;
        let proximity = robot.proximity()?;
        let left: u32 = proximity[0..3].iter().map(|&v| v as u32).sum();
        let right: u32 = proximity[3..6].iter().map(|&v| v as u32).sum();
        let (speed_left, speed_right) = if left + right < 300 {
            (12, 12)
        } else if left > right {
            (8, -8) // obstacle on the left: turn right on the spot
        } else {
            (-8, 8)
        };
        robot.set_led(
            0,
            if (speed_left, speed_right) == (12, 12) {
                LedAction::Off
            } else {
                LedAction::Toggle
            },
        )?;
        robot.set_speed(speed_left, speed_right)
    }
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let world = std::env::args()
        .nth(1)
        .unwrap_or_else(|| "worlds/regatta.wbt".to_owned());
    let checked = regatta_schema::check_file(std::path::Path::new(&world), true)?;
    if checked.has_errors() {
        eprint!("{}", checked.render(false));
        return Err(format!("{world} has errors").into());
    }
    let compiled = regatta_runtime::compile(&checked.scene);
    let mut simulation = Simulation::new(&compiled, None)?;
    // Replace the world's controller of robot 0 with ours.
    simulation.set_controller(0, Box::new(Wanderer { steps: 0 }));
    simulation.run((60.0 / simulation.time_step) as u64);
    let robot = &simulation.robots[0];
    println!(
        "after {:.0} s: {} at x {:.3} z {:.3}, {} contacts, LEDs {:?}",
        simulation.time, robot.name, robot.pose.x, robot.pose.z, robot.contacts.events, robot.leds
    );
    Ok(())
}
