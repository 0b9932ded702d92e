//! What one sensor brings to a correction: its evidence and its innovation.
//!
//! Each sensor's averaged measurement becomes, at a correction, one [`Evidence`] item: the
//! Bingham exponent of its likelihood (multiplied into the state in the one Bayes product of
//! the correction, module `correction`) and its [`Innovation`] against the prior — what the
//! measurement says minus what the prior predicts, with its degrees of freedom and the
//! measurement's variance. The health readout (module `health`) normalizes the innovation by
//! the variance it should have; the bias learning (module `correction`) reads its angle (a
//! recovery from a large error teaches the bias nothing) and whether the item observes the
//! heading. A new sensor adds its own item; the correction, the bias learning and the readout
//! read the list.

use nalgebra::{Matrix4, Vector3};

/// One sensor's evidence of a correction period, relative to the prior of the correction.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct Evidence {
    /// The likelihood's Bingham exponent (symmetric 4×4, `exp(qᵀ E q)`).
    pub(super) exponent: Matrix4<f64>,
    /// The measurement against the prior's prediction.
    pub(super) innovation: Innovation,
    /// The measurement's own variance (rad²) per degree of freedom of the innovation: what the
    /// innovation's variance would be with a certain prior.
    pub(super) var: f64,
}

/// An innovation: the measured minus the predicted part of the orientation a sensor observes.
#[derive(Debug, Clone, PartialEq)]
pub(super) enum Innovation {
    /// The tilt (2 degrees of freedom): the observed body-frame "up" against the predicted
    /// one, `up` (unit).
    Tilt {
        /// The prior's body-frame "up" (unit).
        up: Vector3<f64>,
        /// The innovation as a vector perpendicular to `up`, towards the observed "up", of
        /// length `angle`.
        e: Vector3<f64>,
        /// The angle (rad, ≥ 0) between the predicted and the observed "up".
        angle: f64,
    },
    /// The heading (1 degree of freedom): a rotation about the world vertical.
    Heading {
        /// The prior's body-frame "up" (unit): the axis of the rotation in the body frame.
        up: Vector3<f64>,
        /// The heading error (rad, signed) about the world vertical.
        angle: f64,
    },
}

impl Innovation {
    /// The tilt innovation of the observed body-frame "up" `observed` (unit) against the
    /// predicted `predicted` (unit): the angle between them along the great circle, as a
    /// vector in the plane perpendicular to `predicted`.
    pub(super) fn tilt(predicted: &[f64; 3], observed: &[f64; 3]) -> Innovation {
        let bh = Vector3::from(*predicted);
        let b = Vector3::from(*observed);
        let c = bh.cross(&b);
        let angle = c.norm().atan2(bh.dot(&b));
        // the innovation as a vector in the plane perpendicular to b̂, towards b
        let dir = b - bh * bh.dot(&b);
        let e = if dir.norm() > 0.0 {
            dir.normalize() * angle
        } else {
            Vector3::zeros()
        };
        Innovation::Tilt { up: bh, e, angle }
    }

    /// The heading innovation `delta` (rad, about the world vertical) with the predicted
    /// body-frame "up" `predicted` (unit).
    pub(super) fn heading(predicted: &[f64; 3], delta: f64) -> Innovation {
        Innovation::Heading {
            up: Vector3::from(*predicted),
            angle: delta,
        }
    }

    /// The degrees of freedom: 2 for the tilt, 1 for the heading.
    pub(super) fn dof(&self) -> f64 {
        match self {
            Innovation::Tilt { .. } => 2.0,
            Innovation::Heading { .. } => 1.0,
        }
    }

    /// The size of the innovation (rad, ≥ 0): the angle between the prediction and the
    /// measurement.
    pub(super) fn angle(&self) -> f64 {
        match self {
            Innovation::Tilt { angle, .. } => *angle,
            Innovation::Heading { angle, .. } => angle.abs(),
        }
    }

    /// Whether the measurement observes the heading (without one, the mode may slide about
    /// the vertical: the bias learning then reads only the tilt part of its move).
    pub(super) fn observes_heading(&self) -> bool {
        matches!(self, Innovation::Heading { .. })
    }
}

/// The items present among a correction's per-sensor evidence (`None`: that sensor gave no
/// evidence this period), in the order of the list.
pub(super) fn present(items: &[Option<Evidence>]) -> impl Iterator<Item = &Evidence> {
    items.iter().flatten()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_tilt_innovation_points_from_the_prediction_towards_the_observation() {
        let a: f64 = 0.01;
        let i = Innovation::tilt(&[0.0, 0.0, 1.0], &[a.sin(), 0.0, a.cos()]);
        let Innovation::Tilt { e, angle, .. } = &i else {
            panic!("not a tilt innovation")
        };
        assert!((angle - a).abs() < 1e-15);
        assert!((e - Vector3::new(a, 0.0, 0.0)).norm() < 1e-15);
        assert_eq!(i.dof(), 2.0);
        assert!(!i.observes_heading());
        let h = Innovation::heading(&[0.0, 0.0, 1.0], -0.2);
        assert_eq!((h.dof(), h.angle()), (1.0, 0.2));
        assert!(h.observes_heading());
    }

    #[test]
    fn an_observation_equal_to_the_prediction_has_no_innovation() {
        let i = Innovation::tilt(&[0.0, 0.6, 0.8], &[0.0, 0.6, 0.8]);
        assert_eq!(i.angle(), 0.0);
        let Innovation::Tilt { e, .. } = i else {
            panic!("not a tilt innovation")
        };
        assert_eq!(e, Vector3::zeros());
    }
}
