# SubTask 1: cut the bread into slices (skills: GoToObject, SliceObject, PickupObject)
# SubTask 2: toast one slice (skills: GoToObject, SwitchOn, PickupObject, PutObject)
# SubTask 2 needs the slices SubTask 1 makes, so they run one after the other.

def subtask1_slice_bread():
    # slicing needs a knife in hand
    GoToObject('Knife')
    PickupObject('Knife')
    GoToObject('Bread')
    SliceObject('Bread')

def subtask2_toast_slice():
    # the toaster only takes bread slices
    GoToObject('BreadSliced')
    PickupObject('BreadSliced')
    GoToObject('Toaster')
    PutObject('BreadSliced', 'Toaster')
    SwitchOn('Toaster')

subtask1_slice_bread()
subtask2_toast_slice()
