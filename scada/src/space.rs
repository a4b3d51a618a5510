//! The address space leakwatch adds to the server's: the folder
//! `Objects/Leakwatch`, one object per rig with its state variables
//! ([`crate::state::VARIABLES`], read-only, an `EngineeringUnits` property on
//! those with a unit), and the event type `LeakwatchEventType`
//! ([`crate::event`]) under `BaseEventType`.

use opcua::server::address_space::{
    AccessLevel, AddressSpace, EventNotifier, ObjectBuilder, ObjectTypeBuilder, VariableBuilder,
};
use opcua::types::{
    DataTypeId, EUInformation, LocalizedText, NodeId, ObjectId, ObjectTypeId, QualifiedName, UAString,
    VariableTypeId, Variant,
};

use crate::event::{EventFieldType, EVENT_FIELDS, EVENT_TYPE, NAMESPACE};
use crate::state::{Ty, Unit, VarSpec, VARIABLES};

/// The browse name of the folder of the rigs, under `Objects`.
pub const FOLDER: &str = "Leakwatch";

/// The nodes of one rig.
#[derive(Debug, Clone)]
pub struct RigNodes {
    /// The namespace index of [`NAMESPACE`].
    pub ns: u16,
    /// The rig's id.
    pub rig: String,
    /// The rig's object (its events' SourceNode).
    pub object: NodeId,
    /// Its state variables, in [`VARIABLES`] order.
    pub variables: Vec<NodeId>,
}

/// The node id of a rig's object: `ns=NS;s=<rig>`.
pub fn rig_node(ns: u16, rig: &str) -> NodeId {
    NodeId::new(ns, rig.to_string())
}

/// The node id of a rig's state variable: `ns=NS;s=<rig>.<Name>`.
pub fn variable_node(ns: u16, rig: &str, name: &str) -> NodeId {
    NodeId::new(ns, format!("{rig}.{name}"))
}

fn data_type(ty: Ty) -> DataTypeId {
    match ty {
        Ty::Bool => DataTypeId::Boolean,
        Ty::Double => DataTypeId::Double,
        Ty::Str => DataTypeId::String,
        Ty::U32 => DataTypeId::UInt32,
        Ty::U64 => DataTypeId::UInt64,
    }
}

/// UNECE common code (3 characters at most) → the OPC UA unit id.
fn unece_id(code: &str) -> i32 {
    code.bytes().fold(0, |id, b| (id << 8) | i32::from(b))
}

/// The `EUInformation` of a unit (UNECE Recommendation 20).
pub fn eu_information((symbol, code, description): Unit) -> EUInformation {
    EUInformation {
        namespace_uri: UAString::from("http://www.opcfoundation.org/UA/units/un/cefact"),
        unit_id: unece_id(code),
        display_name: LocalizedText::new("", symbol),
        description: LocalizedText::new("", description),
    }
}

fn add_variable(space: &mut AddressSpace, ns: u16, rig: &str, object: &NodeId, spec: &VarSpec) -> NodeId {
    let id = variable_node(ns, rig, spec.name);
    let read = AccessLevel::CURRENT_READ;
    VariableBuilder::new(&id, QualifiedName::new(ns, spec.name), spec.name)
        .component_of(object.clone())
        .has_type_definition(VariableTypeId::BaseDataVariableType)
        .data_type(data_type(spec.ty))
        .value(Variant::Empty)
        .access_level(read)
        .user_access_level(read)
        .description(spec.doc)
        .insert(space);
    if let Some(unit) = spec.unit {
        let eu = variable_node(ns, rig, &format!("{}.EngineeringUnits", spec.name));
        VariableBuilder::new(&eu, QualifiedName::new(0, "EngineeringUnits"), "EngineeringUnits")
            .property_of(id.clone())
            .has_type_definition(VariableTypeId::PropertyType)
            .data_type(DataTypeId::EUInformation)
            .value(eu_information(unit))
            .access_level(read)
            .user_access_level(read)
            .insert(space);
    }
    id
}

/// Adds `LeakwatchEventType` with its fields as properties.
fn add_event_type(space: &mut AddressSpace, ns: u16) {
    let type_id = NodeId::new(ns, EVENT_TYPE);
    ObjectTypeBuilder::new(&type_id, QualifiedName::new(ns, EVENT_TYPE), EVENT_TYPE)
        .subtype_of(ObjectTypeId::BaseEventType)
        .description("a leakwatch leak or sensor event (raised, updated, cleared)")
        .insert(space);
    for (name, ty, doc) in EVENT_FIELDS {
        let dt = match ty {
            EventFieldType::Str => DataTypeId::String,
            EventFieldType::U64 => DataTypeId::UInt64,
            EventFieldType::Double => DataTypeId::Double,
        };
        VariableBuilder::new(
            &NodeId::new(ns, format!("{EVENT_TYPE}.{name}")),
            QualifiedName::new(ns, name),
            name,
        )
        .property_of(type_id.clone())
        .has_type_definition(VariableTypeId::PropertyType)
        .has_modelling_rule(ObjectId::ModellingRule_Mandatory)
        .data_type(dt)
        .description(doc)
        .insert(space);
    }
}

/// Adds the folder, the event type and rig `rig`'s object with its variables
/// to `space` (namespace `ns`, that of [`NAMESPACE`]).
pub fn build(space: &mut AddressSpace, ns: u16, rig: &str) -> RigNodes {
    debug_assert_eq!(space.namespace_index(NAMESPACE), Some(ns));
    let folder = NodeId::new(ns, FOLDER);
    space.add_folder(
        &folder,
        QualifiedName::new(ns, FOLDER),
        FOLDER,
        &ObjectId::ObjectsFolder.into(),
    );
    add_event_type(space, ns);
    let object = rig_node(ns, rig);
    ObjectBuilder::new(&object, QualifiedName::new(ns, rig), rig)
        .organized_by(folder.clone())
        .has_type_definition(ObjectTypeId::BaseObjectType)
        .event_notifier(EventNotifier::SUBSCRIBE_TO_EVENTS)
        .description(format!("leakwatch rig {rig}: its leak watch, read-only"))
        .insert(space);
    let variables = VARIABLES
        .iter()
        .map(|spec| add_variable(space, ns, rig, &object, spec))
        .collect();
    RigNodes {
        ns,
        rig: rig.to_string(),
        object,
        variables,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn units_have_their_unece_ids() {
        // UNECE ids as the OPC UA specification computes them
        assert_eq!(unece_id("CEL"), 4_408_652);
        assert_eq!(unece_id("SEC"), 5_457_219);
        assert_eq!(
            eu_information(("°C", "CEL", "degree Celsius"))
                .display_name
                .text
                .as_ref(),
            "°C"
        );
    }
}
