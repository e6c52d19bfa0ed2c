//! The `none` controller.

use crate::khepera::{Controller, Khepera, KheperaError, Senses};

/// Does nothing: the robot stays where it is. Its sensors are all refreshed (it declares
/// every one): a robot without a controller is how a world shows what its sensors read. Its
/// 2-D cameras are not (a log or `regatta render` shows their images).
pub struct Idle;

impl Controller for Idle {
    fn step(&mut self, _robot: &mut dyn Khepera) -> Result<(), KheperaError> {
        Ok(())
    }

    fn senses(&self) -> Senses {
        Senses {
            camera: false,
            ..Senses::ALL
        }
    }
}
