//! The spec as written: serde structures that keep the source span of every
//! value, so validation can point at the exact place of a problem.

use serde::de::{Deserialize, Deserializer, MapAccess, Visitor};
use serde_spanned::Spanned;
use std::fmt;
use std::marker::PhantomData;

pub type S<T> = Spanned<T>;

#[derive(Debug, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawSpec {
    pub system: S<RawSystem>,
    #[serde(default)]
    pub channels: Ordered<RawChannel>,
    #[serde(default)]
    pub resources: Ordered<RawResource>,
    #[serde(default)]
    pub threads: Ordered<RawThread>,
    #[serde(default)]
    pub tasks: Ordered<RawTask>,
    #[serde(default)]
    pub chain: Vec<S<RawChain>>,
}

#[derive(Debug, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawSystem {
    pub name: S<String>,
    pub time_unit: Option<S<String>>,
    pub scheduler: Option<S<String>>,
    pub schedulability: Option<S<String>>,
    pub resolution: Option<S<toml::Value>>,
    pub harmonic: Option<S<bool>>,
    pub release: Option<S<String>>,
    pub priorities: Option<S<String>>,
    pub communication: Option<S<String>>,
    pub resource_protocol: Option<S<String>>,
    pub overheads: Option<RawOverheads>,
}

/// `[system] overheads`: the system's costs and per-CPU tables.
#[derive(Debug, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawOverheads {
    pub context_switch: Option<S<toml::Value>>,
    pub release: Option<S<toml::Value>>,
    pub replenish: Option<S<toml::Value>>,
    #[serde(default)]
    pub cpu: Ordered<RawCosts>,
}

/// `[system.overheads.cpu.N]`: the keys one CPU overrides.
#[derive(Debug, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawCosts {
    pub context_switch: Option<S<toml::Value>>,
    pub release: Option<S<toml::Value>>,
    pub replenish: Option<S<toml::Value>>,
}

/// `[resources.NAME]`: no keys yet (the protocol is the system's).
#[derive(Debug, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawResource {}

/// One entry of a task's `critical_sections`.
#[derive(Debug, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawSection {
    pub resource: S<String>,
    pub length: S<toml::Value>,
}

#[derive(Debug, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawChannel {
    pub bandwidth: S<toml::Value>,
    pub overhead: Option<S<toml::Value>>,
}

#[derive(Debug, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawPort {
    pub channel: S<String>,
    pub size: S<toml::Value>,
}

#[derive(Debug, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawTask {
    pub exec: S<toml::Value>,
    pub exec_min: Option<S<toml::Value>>,
    pub input: Option<S<RawPort>>,
    pub output: Option<S<RawPort>>,
    #[serde(default)]
    pub reads: Vec<S<String>>,
    pub period: Option<S<toml::Value>>,
    pub budget: Option<S<toml::Value>>,
    pub server: Option<S<String>>,
    pub cpu: Option<S<toml::Value>>,
    pub serves: Option<S<String>>,
    pub body: Option<S<String>>,
    pub offset: Option<S<toml::Value>>,
    pub priority: Option<S<toml::Value>>,
    pub deadline: Option<S<toml::Value>>,
    pub jitter: Option<S<toml::Value>>,
    pub max_period: Option<S<toml::Value>>,
    pub critical_sections: Option<S<Vec<S<RawSection>>>>,
    pub thread: Option<S<String>>,
    pub activation: Option<S<String>>,
    pub triggers: Option<S<Vec<S<String>>>>,
    pub join: Option<S<String>>,
}

/// `[threads.NAME]`: a work-queue thread.
#[derive(Debug, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawThread {
    pub priority: Option<S<toml::Value>>,
    pub cpu: Option<S<toml::Value>>,
}

#[derive(Debug, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawChain {
    pub path: S<Vec<S<String>>>,
    pub reaction: Option<S<toml::Value>>,
    pub freshness: Option<S<toml::Value>>,
    pub max_reaction_time: Option<S<toml::Value>>,
    pub freshness_from_event: Option<S<toml::Value>>,
    /// The former name of `freshness_from_event`, refused with the new
    /// name: it never limited the literature's maximum data age.
    pub max_data_age: Option<S<toml::Value>>,
    pub name: Option<S<String>>,
    pub communication: Option<S<String>>,
}

/// A TOML table kept in declaration order (task order breaks RM ties), with
/// the span of each key.
#[derive(Debug)]
pub struct Ordered<V>(pub Vec<(S<String>, S<V>)>);

impl<V> Default for Ordered<V> {
    fn default() -> Self {
        Ordered(Vec::new())
    }
}

impl<'de, V: Deserialize<'de>> Deserialize<'de> for Ordered<V> {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V2<V>(PhantomData<V>);
        impl<'de, V: Deserialize<'de>> Visitor<'de> for V2<V> {
            type Value = Ordered<V>;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("a table")
            }
            fn visit_map<A: MapAccess<'de>>(self, mut m: A) -> Result<Self::Value, A::Error> {
                let mut out = Vec::new();
                while let Some((k, v)) = m.next_entry::<S<String>, S<V>>()? {
                    out.push((k, v));
                }
                Ok(Ordered(out))
            }
        }
        d.deserialize_map(V2(PhantomData))
    }
}
