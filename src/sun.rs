//! The sun's position, in one place: declination on a day of the year, the direction of the sun
//! at a latitude, day and hour, the noon sun of the equinox, and the hour of the pictures' sun.
//! Used by the terrain's insolation (`terrain::fields`), the simulation's light
//! (`sim::phases::light`), Plastic Trees' global light (`structure::plastic::light::Sky`) and
//! the renderer (`render::scene::Sun`).
//!
//! Directions are unit vectors in world axes: x east, y north, z up. Angles in the arguments are
//! in degrees (latitude −90..=90, positive north), days of the year 1..=366, hours of local solar
//! time 0..24; results in radians where they are angles.

/// Amplitude of the solar declination (degrees) in Cooper's (1969) formula, `23.45°`
/// (P. I. Cooper, "The absorption of radiation in solar stills", Solar Energy 12:333–346, 1969;
/// the value quoted by Kumar, Skidmore & Knowles 1997, Int. J. GIS 11(5), eq. 2, and by Iqbal
/// 1983, eq. 1.3.1's simple form).
pub const DECLINATION_AMPLITUDE_DEG: f64 = 23.45;

/// Local solar time (hours) of the sun that lights every picture of a season
/// (`job::scene::season_sun`): early afternoon, so that slopes and crowns are lit from the
/// south-west and cast shadows of readable length.
pub const REFERENCE_HOUR: f32 = 14.0;

/// Solar declination (radians) on day `day_of_year` (1..=366):
/// `δ = 23.45° · sin(2π (284 + n) / 365)` (Cooper 1969).
#[inline]
pub fn declination_rad(day_of_year: f64) -> f64 {
    DECLINATION_AMPLITUDE_DEG.to_radians() * (2.0 * std::f64::consts::PI * (284.0 + day_of_year) / 365.0).sin()
}

/// Unit vector from the ground towards the sun, `[east, north, up]`, at latitude `phi_rad`
/// (radians), declination `decl_rad` (radians, [`declination_rad`]) and local solar time `hour`:
/// hour angle `ω = 15° (hour − 12)`, east `= −cos δ sin ω`, north `= sin δ cos φ − cos δ cos ω
/// sin φ`, up `= sin δ sin φ + cos δ cos ω cos φ` (standard spherical astronomy, e.g. Iqbal 1983
/// eq. 1.3.1; Kumar et al. 1997 eqs. 3–5). `up` ≤ 0: the sun is below the horizon.
#[inline]
pub fn direction(phi_rad: f64, decl_rad: f64, hour: f64) -> [f64; 3] {
    let om = (15.0 * (hour - 12.0)).to_radians();
    let e = -decl_rad.cos() * om.sin();
    let n = decl_rad.sin() * phi_rad.cos() - decl_rad.cos() * om.cos() * phi_rad.sin();
    let u = decl_rad.sin() * phi_rad.sin() + decl_rad.cos() * om.cos() * phi_rad.cos();
    [e, n, u]
}

/// [`direction`] at latitude `latitude_deg` (clamped to −90..=90), day `day_of_year` and hour
/// `hour` of local solar time.
pub fn position(latitude_deg: f64, day_of_year: f64, hour: f64) -> [f64; 3] {
    direction(latitude_deg.clamp(-90.0, 90.0).to_radians(), declination_rad(day_of_year), hour)
}

/// Elevation (degrees above the horizon) of the noon sun at an equinox (declination 0) at
/// latitude `latitude_deg` (clamped to −90..=90): `90° − |φ|`. Not clamped further: the
/// simulation's light keeps it within 10–80° for its shading geometry
/// (`sim::phases::light::run`), Plastic Trees' global light takes it as it is.
#[inline]
pub fn noon_equinox_elevation_deg(latitude_deg: f32) -> f32 {
    90.0 - latitude_deg.clamp(-90.0, 90.0).abs()
}

/// The northward component's sign of the noon sun's direction at latitude `latitude_deg`:
/// `−1` (towards the south) on the equator and north of it, `+1` south of it.
#[inline]
pub fn equatorward(latitude_deg: f32) -> f32 {
    if latitude_deg >= 0.0 {
        -1.0
    } else {
        1.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn declination_at_solstices_and_equinoxes() {
        // Cooper's formula peaks at day 172 (21 June) and is about zero at day 81 (22 March)
        assert!((declination_rad(172.0).to_degrees() - 23.45).abs() < 0.01);
        assert!(declination_rad(81.0).to_degrees().abs() < 0.5);
        assert!((declination_rad(355.0).to_degrees() + 23.45).abs() < 0.01);
    }

    #[test]
    fn noon_sun_is_due_south_at_the_equinox_elevation() {
        let [e, n, u] = direction(47f64.to_radians(), 0.0, 12.0);
        assert!(e.abs() < 1e-12 && n < 0.0);
        assert!((u.asin().to_degrees() - noon_equinox_elevation_deg(47.0) as f64).abs() < 1e-4);
        assert_eq!(equatorward(47.0), -1.0);
        assert_eq!(equatorward(-33.0), 1.0);
        // morning sun in the east, afternoon in the west
        assert!(position(47.0, 172.0, 9.0)[0] > 0.3 && position(47.0, 172.0, 15.0)[0] < -0.3);
        let d = position(47.0, 200.0, 10.0);
        assert!((d[0] * d[0] + d[1] * d[1] + d[2] * d[2] - 1.0).abs() < 1e-12);
    }
}
