//! The Global section: delimiters, sender information, units, scales and tolerances.

use crate::param::{Param, split};

/// The 26 parameters of the Global section (IGES 5.3, §2.2.4.3).
///
/// Empty parameters read as the specification's defaults (empty strings, 0, model scale 1,
/// units flag 1).
#[derive(Debug, Clone, PartialEq)]
pub struct Global {
    /// 1: parameter delimiter (default `,`).
    pub param_delim: u8,
    /// 2: record delimiter (default `;`).
    pub record_delim: u8,
    /// 3: product identification from the sender.
    pub sender_product_id: String,
    /// 4: file name.
    pub file_name: String,
    /// 5: native system identification.
    pub native_system_id: String,
    /// 6: preprocessor version.
    pub preprocessor_version: String,
    /// 7: number of binary bits for integer representation.
    pub integer_bits: i64,
    /// 8: maximum power of ten representable in single precision.
    pub single_max_power: i64,
    /// 9: significant digits in single precision.
    pub single_digits: i64,
    /// 10: maximum power of ten representable in double precision.
    pub double_max_power: i64,
    /// 11: significant digits in double precision.
    pub double_digits: i64,
    /// 12: product identification for the receiver.
    pub receiver_product_id: String,
    /// 13: model space scale (model units per real-world unit).
    pub model_scale: f64,
    /// 14: units flag (1 inch, 2 mm, 3 named by parameter 15, 4 foot, 5 mile, 6 metre,
    /// 7 km, 8 mil, 9 micron, 10 cm, 11 microinch).
    pub units_flag: i64,
    /// 15: units name (`"MM"`, `"IN"`, `"M"`...).
    pub units_name: String,
    /// 16: maximum number of line weight gradations.
    pub line_weight_grades: i64,
    /// 17: width of the maximum line weight, in units.
    pub max_line_width: f64,
    /// 18: date and time of file generation (`YYMMDD.HHNNSS` or `YYYYMMDD.HHNNSS`).
    pub date: String,
    /// 19: minimum user-intended resolution (the model's tolerance), in units.
    pub resolution: f64,
    /// 20: approximate maximum coordinate value, in units.
    pub max_coordinate: f64,
    /// 21: author.
    pub author: String,
    /// 22: author's organisation.
    pub organization: String,
    /// 23: version flag (11 = IGES 5.3).
    pub version: i64,
    /// 24: drafting standard flag.
    pub drafting_standard: i64,
    /// 25: date and time the model was created or modified.
    pub modified_date: String,
    /// 26: application protocol or subset identifier.
    pub application_protocol: String,
}

impl Default for Global {
    fn default() -> Self {
        Global {
            param_delim: b',',
            record_delim: b';',
            sender_product_id: String::new(),
            file_name: String::new(),
            native_system_id: String::new(),
            preprocessor_version: String::new(),
            integer_bits: 32,
            single_max_power: 38,
            single_digits: 6,
            double_max_power: 308,
            double_digits: 15,
            receiver_product_id: String::new(),
            model_scale: 1.0,
            units_flag: 2,
            units_name: "MM".into(),
            line_weight_grades: 1,
            max_line_width: 0.0,
            date: String::new(),
            resolution: 0.0,
            max_coordinate: 0.0,
            author: String::new(),
            organization: String::new(),
            version: 11,
            drafting_standard: 0,
            modified_date: String::new(),
            application_protocol: String::new(),
        }
    }
}

impl Global {
    /// The length of one model unit in millimetres, from the units flag (and the units
    /// name when the flag is 3); `None` when the unit is not recognised.
    pub fn unit_in_mm(&self) -> Option<f64> {
        let by_flag = |f: i64| match f {
            1 => Some(25.4),
            2 => Some(1.0),
            4 => Some(304.8),
            5 => Some(1_609_344.0),
            6 => Some(1000.0),
            7 => Some(1.0e6),
            8 => Some(0.0254),
            9 => Some(0.001),
            10 => Some(10.0),
            11 => Some(2.54e-5),
            _ => None,
        };
        if self.units_flag == 3 {
            let flag = match self.units_name.trim().to_ascii_uppercase().as_str() {
                "IN" | "INCH" => 1,
                "MM" => 2,
                "FT" => 4,
                "MI" => 5,
                "M" => 6,
                "KM" => 7,
                "MIL" => 8,
                "UM" => 9,
                "CM" => 10,
                "UIN" => 11,
                _ => 0,
            };
            by_flag(flag)
        } else {
            by_flag(self.units_flag)
        }
    }

    /// Parses the Global section text (columns 1–72 of all `G` lines, concatenated).
    pub(crate) fn parse(text: &[u8]) -> Result<Global, (usize, String)> {
        let mut g = Global::default();
        let mut pos = 0usize;
        let skip = |pos: &mut usize| {
            while *pos < text.len() && text[*pos] == b' ' {
                *pos += 1;
            }
        };
        // Parameter 1: "1Hc" or empty (default ',').
        skip(&mut pos);
        let pd = if text[pos..].starts_with(b"1H") {
            let c = *text
                .get(pos + 2)
                .ok_or((1, "truncated delimiter".to_string()))?;
            pos += 3;
            skip(&mut pos);
            match text.get(pos) {
                Some(&d) if d == c => pos += 1,
                other => {
                    return Err((
                        1,
                        format!(
                            "expected the delimiter '{}' after 1H{}, found {}",
                            c as char,
                            c as char,
                            other.map_or("the end".into(), |&b| format!("'{}'", b as char))
                        ),
                    ));
                }
            }
            c
        } else if text.get(pos) == Some(&b',') {
            pos += 1;
            b','
        } else {
            return Err((
                1,
                "expected the parameter delimiter as 1Hc or an empty field".into(),
            ));
        };
        // Parameter 2: "1Hc" or empty (default ';').
        skip(&mut pos);
        let rd = if text[pos.min(text.len())..].starts_with(b"1H") {
            let c = *text
                .get(pos + 2)
                .ok_or((2, "truncated delimiter".to_string()))?;
            pos += 3;
            c
        } else {
            b';'
        };
        if pd == rd || pd == b' ' || rd == b' ' || pd.is_ascii_digit() || rd.is_ascii_digit() {
            return Err((2, "unusable delimiters".into()));
        }
        g.param_delim = pd;
        g.record_delim = rd;
        skip(&mut pos);
        let rest = &text[pos.min(text.len())..];
        let params = match rest.first() {
            Some(&c) if c == rd => Vec::new(),
            Some(&c) if c == pd => split(&rest[1..], pd, rd, 3).map_err(|e| (e.index, e.reason))?,
            _ => {
                return Err((
                    2,
                    "expected a delimiter after the record delimiter definition".into(),
                ));
            }
        };
        let get = |i: usize| params.get(i - 3).unwrap_or(&Param::Empty);
        let string = |i: usize| -> Result<Option<String>, (usize, String)> {
            match get(i) {
                Param::Empty => Ok(None),
                Param::Str(s) => Ok(Some(s.clone())),
                p => Err((i, format!("expected a string, found '{}'", p.describe()))),
            }
        };
        let int = |i: usize| -> Result<Option<i64>, (usize, String)> {
            match get(i) {
                Param::Empty => Ok(None),
                Param::Int(v) => Ok(Some(*v)),
                p => Err((i, format!("expected an integer, found '{}'", p.describe()))),
            }
        };
        let real = |i: usize| -> Result<Option<f64>, (usize, String)> {
            match get(i) {
                Param::Empty => Ok(None),
                Param::Int(v) => Ok(Some(*v as f64)),
                Param::Real(v) => Ok(Some(*v)),
                p => Err((i, format!("expected a real, found '{}'", p.describe()))),
            }
        };
        macro_rules! set {
            ($f:ident, $how:ident, $i:expr) => {
                if let Some(v) = $how($i)? {
                    g.$f = v;
                }
            };
        }
        g.units_name = String::new();
        set!(sender_product_id, string, 3);
        set!(file_name, string, 4);
        set!(native_system_id, string, 5);
        set!(preprocessor_version, string, 6);
        set!(integer_bits, int, 7);
        set!(single_max_power, int, 8);
        set!(single_digits, int, 9);
        set!(double_max_power, int, 10);
        set!(double_digits, int, 11);
        set!(receiver_product_id, string, 12);
        set!(model_scale, real, 13);
        g.units_flag = 1;
        set!(units_flag, int, 14);
        set!(units_name, string, 15);
        set!(line_weight_grades, int, 16);
        set!(max_line_width, real, 17);
        set!(date, string, 18);
        set!(resolution, real, 19);
        set!(max_coordinate, real, 20);
        set!(author, string, 21);
        set!(organization, string, 22);
        set!(version, int, 23);
        set!(drafting_standard, int, 24);
        set!(modified_date, string, 25);
        set!(application_protocol, string, 26);
        if g.model_scale <= 0.0 {
            return Err((
                13,
                format!("model space scale {} is not positive", g.model_scale),
            ));
        }
        if g.resolution < 0.0 {
            return Err((
                19,
                format!("minimum resolution {} is negative", g.resolution),
            ));
        }
        Ok(g)
    }

    /// The Global section parameters for writing (parameters 3–26; the delimiters are
    /// written separately).
    pub(crate) fn params(&self) -> Vec<Param> {
        let s = |x: &String| Param::Str(x.clone());
        vec![
            s(&self.sender_product_id),
            s(&self.file_name),
            s(&self.native_system_id),
            s(&self.preprocessor_version),
            Param::Int(self.integer_bits),
            Param::Int(self.single_max_power),
            Param::Int(self.single_digits),
            Param::Int(self.double_max_power),
            Param::Int(self.double_digits),
            s(&self.receiver_product_id),
            Param::Real(self.model_scale),
            Param::Int(self.units_flag),
            s(&self.units_name),
            Param::Int(self.line_weight_grades),
            Param::Real(self.max_line_width),
            s(&self.date),
            Param::Real(self.resolution),
            Param::Real(self.max_coordinate),
            s(&self.author),
            s(&self.organization),
            Param::Int(self.version),
            Param::Int(self.drafting_standard),
            s(&self.modified_date),
            s(&self.application_protocol),
        ]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_solidworks_global() {
        let text = b"1H,,1H;,19Hgeom_oneram6.SLDPRT,4Habcd,15HSolidWorks 2013,15HSolidWorks 2013,32,308,15,308,15,19Hgeom_oneram6.SLDPRT,1.,6,1HM,50,0.125,13H140110.003157,1E-008,499.99,5HTrent,,11,0,13H140110.003157;";
        let g = Global::parse(text).unwrap();
        assert_eq!(g.sender_product_id, "geom_oneram6.SLDPRT");
        assert_eq!(g.units_flag, 6);
        assert_eq!(g.unit_in_mm(), Some(1000.0));
        assert_eq!(g.resolution, 1e-8);
        assert_eq!(g.max_coordinate, 499.99);
        assert_eq!(g.organization, "");
        assert_eq!(g.version, 11);
    }

    #[test]
    fn default_and_custom_delimiters() {
        let g = Global::parse(b",,3Habc,;").unwrap();
        assert_eq!((g.param_delim, g.record_delim), (b',', b';'));
        assert_eq!(g.sender_product_id, "abc");
        let g = Global::parse(b"1H//1H$/3Habc/ /5Hx/y z//32$").unwrap();
        assert_eq!((g.param_delim, g.record_delim), (b'/', b'$'));
        assert_eq!(g.file_name, "");
        assert_eq!(g.native_system_id, "x/y z");
        assert_eq!(g.preprocessor_version, "");
        assert_eq!(g.integer_bits, 32);
        assert!(Global::parse(b"1H/,1H$/3Habc/ /x$").is_err());
        let (i, _) = Global::parse(b"1H,,1H;,,,,,,,,,,,-1.;").unwrap_err();
        assert_eq!(i, 13);
    }
}
