# SubTask 1: cut the bread into slices (skills: GoToObject, SliceObject, PickupObject, DropHandObject)
# SubTask 2: toast one slice (skills: GoToObject, SwitchOn, PickupObject, PutObject)
# SubTask 2 needs the slices SubTask 1 makes, so they run one after the other.

def subtask1_slice_bread():
    # slicing needs a knife in hand: fetch one
    GoToObject('Knife')
    # hold the knife
    PickupObject('Knife')
    # go to the loaf
    GoToObject('Bread')
    # cut it into slices
    SliceObject('Bread')
    # lay the knife down where it stands
    DropHandObject('Knife')

def subtask2_toast_slice():
    # go to one of the new slices
    GoToObject('BreadSliced')
    # pick the slice up
    PickupObject('BreadSliced')
    # carry it to the toaster
    GoToObject('Toaster')
    # the toaster only takes bread slices
    PutObject('BreadSliced', 'Toaster')
    # start toasting
    SwitchOn('Toaster')

subtask1_slice_bread()
subtask2_toast_slice()
