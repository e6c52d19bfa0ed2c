//! The simulated robot behind the Khepera API: wheel commands, encoders, readings, LEDs, and
//! its devices' turret and camera interfaces.

use super::state::{CameraState, LinearCameraState, PanoramicState, RobotState};
use crate::compile::rig::RobotRig;
use crate::khepera::{Khepera, KheperaError, LedAction, LinearCameraTurret, PanoramicTurret};
use crate::retina::FilterKind;

/// The simulated robot behind the Khepera API.
pub struct SimulatedKhepera<'a> {
    pub(super) robot: &'a mut RobotState,
    pub(super) rig: &'a RobotRig,
}

impl Khepera for SimulatedKhepera<'_> {
    fn set_speed(&mut self, left: i32, right: i32) -> Result<(), KheperaError> {
        for value in [left, right] {
            if !(-127..=127).contains(&value) {
                return Err(KheperaError::OutOfRange {
                    what: "wheel speed",
                    value: value as i64,
                    range: "-127…127",
                });
            }
        }
        self.robot.command = (left, right);
        Ok(())
    }

    fn speed(&mut self) -> Result<(i32, i32), KheperaError> {
        Ok(self.robot.command)
    }

    fn position(&mut self) -> Result<(i32, i32), KheperaError> {
        Ok(self.robot.counters(self.rig))
    }

    fn set_position(&mut self, left: i32, right: i32) -> Result<(), KheperaError> {
        let raw = |travel: f64| libm::floor(travel * self.rig.encoder_resolution) as i64;
        self.robot.counter_offset = (
            raw(self.robot.travel.0) - left as i64,
            raw(self.robot.travel.1) - right as i64,
        );
        Ok(())
    }

    fn proximity(&mut self) -> Result<[u16; 8], KheperaError> {
        if !self.robot.senses.proximity {
            return Err(KheperaError::NotSensed("proximity sensors"));
        }
        Ok(self.robot.proximity)
    }

    fn ambient(&mut self) -> Result<[u16; 8], KheperaError> {
        if !self.robot.senses.ambient {
            return Err(KheperaError::NotSensed("ambient light sensors"));
        }
        Ok(self.robot.ambient)
    }

    fn set_led(&mut self, led: u8, action: LedAction) -> Result<(), KheperaError> {
        let slot = self
            .robot
            .leds
            .get_mut(led as usize)
            .ok_or(KheperaError::OutOfRange {
                what: "LED",
                value: led as i64,
                range: "0…1",
            })?;
        *slot = match action {
            LedAction::Off => false,
            LedAction::On => true,
            LedAction::Toggle => !*slot,
        };
        Ok(())
    }

    fn panoramic(&mut self) -> Option<&mut dyn PanoramicTurret> {
        self.robot
            .panoramic
            .as_mut()
            .map(|p| &mut **p as &mut dyn PanoramicTurret)
    }

    fn linear_camera(&mut self) -> Option<&mut dyn LinearCameraTurret> {
        self.robot
            .linear_camera
            .as_mut()
            .map(|c| &mut **c as &mut dyn LinearCameraTurret)
    }

    fn cameras(&mut self) -> Vec<&mut dyn crate::khepera::Camera> {
        self.robot
            .cameras
            .iter_mut()
            .map(|c| c as &mut dyn crate::khepera::Camera)
            .collect()
    }
}

impl crate::khepera::Camera for CameraState {
    fn name(&self) -> &str {
        &self.model.rig.name
    }

    fn size(&self) -> (usize, usize) {
        (self.model.rig.width, self.model.rig.height)
    }

    fn image(&mut self) -> Result<Vec<u8>, KheperaError> {
        if !self.sensed {
            return Err(KheperaError::NotSensed("camera"));
        }
        Ok(self.image.rgb.clone())
    }
}

impl PanoramicState {
    fn reconfigure(&mut self, change: impl FnOnce(&mut crate::compile::rig::PanoramicRig)) {
        let mut rig = self.model.rig.clone();
        change(&mut rig);
        self.model.reconfigure(rig);
        // Filters depend on analog[] alone: recompute them now rather than at the next update.
        if !self.output.analog.is_empty() {
            self.model.refilter(&mut self.output);
        }
    }
}

impl PanoramicTurret for PanoramicState {
    fn enable_filter(&mut self, filter: FilterKind) -> Result<(), KheperaError> {
        if !self.model.rig.filters.contains(filter) {
            self.reconfigure(|rig| rig.filters.insert(filter));
        }
        Ok(())
    }

    fn disable_filter(&mut self, filter: FilterKind) -> Result<(), KheperaError> {
        if self.model.rig.filters.contains(filter) {
            self.reconfigure(|rig| rig.filters.remove(filter));
        }
        Ok(())
    }

    fn read(&mut self, filter: FilterKind) -> Result<Vec<u16>, KheperaError> {
        let mut out = Vec::new();
        self.read_into(filter, &mut out)?;
        Ok(out)
    }

    fn read_into(&mut self, filter: FilterKind, out: &mut Vec<u16>) -> Result<(), KheperaError> {
        if !self.sensed {
            return Err(KheperaError::NotSensed("Panoramic turret"));
        }
        if !self.model.rig.filters.contains(filter) {
            return Err(KheperaError::FilterNotEnabled(filter.name()));
        }
        out.clear();
        if let Some((_, digital)) = self.output.digital.iter().find(|(k, _)| *k == filter) {
            out.extend_from_slice(digital);
        }
        Ok(())
    }

    fn set_lambda(&mut self, lambda: f64) -> Result<(), KheperaError> {
        if !(lambda > 0.0 && lambda.is_finite()) {
            return Err(KheperaError::OutOfRange {
                what: "λ (×1000)",
                value: (lambda * 1000.0) as i64,
                range: "> 0",
            });
        }
        self.reconfigure(|rig| rig.lambda = lambda);
        Ok(())
    }

    fn set_bits(&mut self, bits: u32) -> Result<(), KheperaError> {
        if !(1..=16).contains(&bits) {
            return Err(KheperaError::OutOfRange {
                what: "bits",
                value: bits as i64,
                range: "1…16",
            });
        }
        self.reconfigure(|rig| rig.bits = bits);
        Ok(())
    }

    fn set_region_of_interest(&mut self, first: usize, last: usize) -> Result<(), KheperaError> {
        if first > last || last >= crate::retina::PIXELS {
            return Err(KheperaError::OutOfRange {
                what: "region of interest end",
                value: last as i64,
                range: "first ≤ last ≤ 149",
            });
        }
        self.reconfigure(|rig| rig.roi = (first, last));
        Ok(())
    }

    fn region_of_interest(&mut self) -> Result<(usize, usize), KheperaError> {
        Ok(self.model.rig.roi)
    }

    fn bits(&mut self) -> Result<u32, KheperaError> {
        Ok(self.model.rig.bits)
    }

    fn lambda(&mut self) -> Result<f64, KheperaError> {
        Ok(self.model.rig.lambda)
    }
}

impl LinearCameraTurret for LinearCameraState {
    fn pixels(&mut self) -> Result<Vec<u16>, KheperaError> {
        if !self.sensed {
            return Err(KheperaError::NotSensed("K213 camera"));
        }
        Ok(self.output.digital.clone())
    }

    fn light_level(&mut self) -> Result<u16, KheperaError> {
        if !self.sensed {
            return Err(KheperaError::NotSensed("K213 camera"));
        }
        Ok(self.output.light_level)
    }
}
